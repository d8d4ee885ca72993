// Runs the headless CLI (the same modules on Dawn) from a page test, for
// comparisons between what the page shows and what the CLI computes.
import { execFile } from 'node:child_process';
import { mkdtempSync, readFileSync } from 'node:fs';
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
