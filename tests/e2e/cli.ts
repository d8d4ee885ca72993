// Runs the headless CLI (the same modules on Dawn) from a page test, for
// comparisons between what the page shows and what the CLI computes.
import { execFile, execFileSync } from 'node:child_process';
import { mkdirSync, mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';

const root = fileURLToPath(new URL('../../', import.meta.url));
export const SHARED_VOLUMES_DIR = join(root, '..', 'shared', 'data', 'volumes');

/** `npm run cli -- <args> --json OUT`, returning the parsed JSON. */
export function runCli<T = Record<string, unknown>>(args: string[]): Promise<T> {
  const out = join(mkdtempSync(join(tmpdir(), 'zfpiso-cli-')), 'out.json');
  return new Promise((resolve, reject) => {
    execFile(
      process.execPath,
      [join(root, 'scripts', 'cli.mjs'), ...args, '--json', out],
      { cwd: root, timeout: 600_000 },
      (error, stdout, stderr) => {
        if (error) reject(new Error(`cli ${args.join(' ')} failed: ${error.message}\n${stdout}\n${stderr}`));
        else resolve(JSON.parse(readFileSync(out, 'utf8')) as T);
      },
    );
  });
}

/** The preview server's stores folder (/stores/ serves it). */
export const E2E_STORES_DIR = join(root, 'test-results', 'stores');

/** The neghip volume converted into test-results/stores/NAME (16^3 chunks, rate 8, shards of 2^3), made again each run. */
export function convertNeghipStore(name: string): string {
  const out = join(E2E_STORES_DIR, name);
  rmSync(out, { recursive: true, force: true });
  mkdirSync(E2E_STORES_DIR, { recursive: true });
  execFileSync(
    process.execPath,
    [
      join(root, 'scripts/convert.mjs'),
      join(SHARED_VOLUMES_DIR, 'neghip_66x66x66_uint8.raw'),
      '--out',
      out,
      '--chunk',
      '16',
      '--rate',
      '8',
      '--shard',
      '2',
      '--quiet',
    ],
    { timeout: 600_000 },
  );
  return out;
}
