#!/usr/bin/env node
// `npm run bench:gpu [-- args]`: installs what the benchmark needs here (npm
// packages; the Vulkan loader, and Chromium for its SwiftShader driver where
// there is no GPU; the converter's Python environment for the streamed
// store), then runs benchmarks/gpu/run.ts. `-- --pack` makes the bundle for a
// lent GPU machine instead (pack.mjs); `-- --compare A.json B.json` compares
// two results.
import { spawnSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { ensureConverterEnv } from '../../scripts/setup/converter-env.mjs';
import { ensureNodeModules } from '../../scripts/setup/npm-deps.mjs';
import { ensureSystemPackages, hasGpuDeviceNodes } from '../../scripts/setup/system-deps.mjs';

const root = fileURLToPath(new URL('../..', import.meta.url));
const args = process.argv.slice(2);
ensureNodeModules(root, { quiet: true });
if (args.includes('--pack')) {
  const { pack } = await import('./pack.mjs');
  try {
    await pack();
  } catch (e) {
    console.error(`[pack] ${e.message}`);
    process.exit(1);
  }
  process.exit(0);
}
if (!args.includes('--compare')) {
  try {
    ensureSystemPackages({ chromium: !hasGpuDeviceNodes(), purpose: 'bench:gpu' });
    ensureConverterEnv(root);
  } catch (e) {
    console.error(`[setup] ${e.message}`);
    process.exit(1);
  }
}
const r = spawnSync(
  process.execPath,
  [
    '--import',
    new URL('../../scripts/register-node-loaders.mjs', import.meta.url).href,
    fileURLToPath(new URL('./run.ts', import.meta.url)),
    ...args,
  ],
  { cwd: process.env.INIT_CWD ?? process.cwd(), stdio: 'inherit' },
);
process.exit(r.status ?? 1);
