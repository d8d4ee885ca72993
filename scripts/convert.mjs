#!/usr/bin/env node
// `npm run convert -- IN --out STORE.zarr [...]`: the Python converter
// (converter/, `python -m zfpzarr`) in its own environment, made on first use.
import { spawnSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { converterEnv, ensureConverterEnv } from './setup/converter-env.mjs';

const root = fileURLToPath(new URL('..', import.meta.url));
let python;
try {
  python = ensureConverterEnv(root);
} catch (e) {
  console.error(`[setup] ${e.message}`);
  process.exit(1);
}
// Paths on the command line are relative to where npm was started.
const cwd = process.env.INIT_CWD ?? process.cwd();
const r = spawnSync(python, ['-m', 'zfpzarr', ...process.argv.slice(2)], { cwd, stdio: 'inherit', env: converterEnv(root) });
process.exit(r.status ?? 1);
