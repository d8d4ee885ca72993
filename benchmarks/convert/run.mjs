#!/usr/bin/env node
// `npm run bench:convert [-- --big none | --repeats N ...]`: benchmarks/convert/bench.py
// in the converter's environment (made on first use).
import { spawnSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { join } from 'node:path';
import { converterEnv, ensureConverterEnv } from '../../scripts/setup/converter-env.mjs';

const root = fileURLToPath(new URL('../..', import.meta.url));
const python = ensureConverterEnv(root);
const r = spawnSync(python, [join(root, 'benchmarks/convert/bench.py'), ...process.argv.slice(2)], {
  stdio: 'inherit',
  env: converterEnv(root),
});
process.exit(r.status ?? 1);
