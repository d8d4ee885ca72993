// Debian's Chromium with WebGPU on SwiftShader, drawing to a canvas. Which
// flags do that depends on the machine's graphics stack, so the set is probed
// once by scripts/setup/chromium-flags.mjs (cached in .cache/) and used by
// every launch: Playwright's config, the e2e helpers and the benchmarks.
import { spawnSync } from 'node:child_process';
import { existsSync } from 'node:fs';
import { fileURLToPath } from 'node:url';

export interface ChromiumLaunch {
  /** The candidate that drew, e.g. "ANGLE on SwiftShader". */
  name: string;
  executablePath: string;
  args: string[];
  /** Extra environment for Chromium (added to process.env). */
  env: Record<string, string>;
  /** `chromium --version`. */
  chromium: string;
}

const PROBE = fileURLToPath(new URL('../../scripts/setup/chromium-flags.mjs', import.meta.url));

export function chromiumPath(): string {
  const candidates = [process.env.CHROMIUM_PATH, '/usr/bin/chromium', '/usr/bin/chromium-browser'].filter((p): p is string => !!p);
  return candidates.find((p) => existsSync(p)) ?? '/usr/bin/chromium';
}

let launch: ChromiumLaunch | undefined;

/** The probed flag set (synchronous, so configs can use it); throws with the probe's message if none draws. */
export function chromiumWebGpuLaunch(): ChromiumLaunch {
  if (launch) return launch;
  const r = spawnSync(process.execPath, [PROBE, '--json'], { encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'], timeout: 600_000 });
  if (r.status !== 0) throw new Error(`${r.stderr.trim() || `the Chromium flag probe (${PROBE}) exited with ${r.status}`}`);
  if (r.stderr.trim()) process.stderr.write(r.stderr);
  launch = JSON.parse(r.stdout) as ChromiumLaunch;
  return launch;
}

/** Playwright launch options for the probed set. */
export function chromiumLaunchOptions(): { executablePath: string; args: string[]; env: Record<string, string> } {
  const l = chromiumWebGpuLaunch();
  const env: Record<string, string> = {};
  for (const [k, v] of Object.entries(process.env)) if (v !== undefined) env[k] = v;
  return { executablePath: l.executablePath, args: l.args, env: { ...env, ...l.env } };
}
