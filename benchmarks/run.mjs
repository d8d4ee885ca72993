#!/usr/bin/env node
// Runs a TypeScript benchmark with the same loaders as the CLI:
//   node benchmarks/run.mjs benchmarks/<name>.ts [args]
import { spawnSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { resolve } from 'node:path';
import { ensureNodeModules } from '../scripts/setup/npm-deps.mjs';
import { ensurePythonEnv } from '../scripts/setup/python-env.mjs';
import { ensureSystemPackages, hasGpuDeviceNodes } from '../scripts/setup/system-deps.mjs';

const root = fileURLToPath(new URL('..', import.meta.url));
ensureNodeModules(root, { quiet: true });
const [script, ...args] = process.argv.slice(2);
if (!script) {
  console.error('usage: node benchmarks/run.mjs benchmarks/<name>.ts [args]');
  process.exit(2);
}
// What the benchmarks need besides npm packages: the Vulkan loader for Dawn,
// Chromium (SwiftShader where there is no GPU; the browser of bench:paper),
// and the Python .venv with the reference tools (zfpy, VTK, laspy, tifffile).
try {
  ensureSystemPackages({ chromium: !hasGpuDeviceNodes() || script.includes('paper'), purpose: 'the benchmarks' });
  ensurePythonEnv(root);
} catch (e) {
  console.error(`[setup] ${e.message}`);
  process.exit(1);
}
const r = spawnSync(
  process.execPath,
  ['--import', new URL('../scripts/register-node-loaders.mjs', import.meta.url).href, resolve(root, script), ...args],
  {
    cwd: process.env.INIT_CWD ?? process.cwd(),
    stdio: 'inherit',
  },
);
process.exit(r.status ?? 1);
