#!/usr/bin/env node
// `npm run cli -- <command> [options]`: the headless runner. Starts Node with
// the TypeScript and `?raw` loaders so the CLI runs the same modules as the
// page. Relative paths are taken from the directory npm was called in.
import { spawnSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { ensureNodeModules } from './setup/npm-deps.mjs';

const root = fileURLToPath(new URL('..', import.meta.url));
ensureNodeModules(root, { quiet: true });
const result = spawnSync(
  process.execPath,
  [
    '--import', new URL('./register-node-loaders.mjs', import.meta.url).href,
    fileURLToPath(new URL('../src/cli/main.ts', import.meta.url)),
    ...process.argv.slice(2),
  ],
  { cwd: process.env.INIT_CWD ?? process.cwd(), stdio: 'inherit' },
);
process.exit(result.status ?? 1);
