#!/usr/bin/env node
// `npm run cli -- <command> [options]`: the headless runner. Starts Node with
// the TypeScript and `?raw` loaders so the CLI runs the same modules as the
// page. Relative paths are taken from the directory npm was called in.
import { spawnSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { ensureNodeModules } from './setup/npm-deps.mjs';
import { ensureSystemPackages, hasGpuDeviceNodes } from './setup/system-deps.mjs';

const root = fileURLToPath(new URL('..', import.meta.url));
ensureNodeModules(root, { quiet: true });
// Dawn needs the Vulkan loader, and SwiftShader (from Debian's chromium) where
// there is no GPU: installed here when root, else the command is printed and
// the CLI goes on (help works; GPU commands then fail saying the same).
try {
  ensureSystemPackages({ chromium: !hasGpuDeviceNodes(), purpose: 'the CLI (WebGPU in Node through Dawn)', quiet: true });
} catch (e) {
  console.error(`warning: ${e.message}`);
}
const result = spawnSync(
  process.execPath,
  [
    '--import',
    new URL('./register-node-loaders.mjs', import.meta.url).href,
    fileURLToPath(new URL('../src/cli/main.ts', import.meta.url)),
    ...process.argv.slice(2),
  ],
  { cwd: process.env.INIT_CWD ?? process.cwd(), stdio: 'inherit' },
);
process.exit(result.status ?? 1);
