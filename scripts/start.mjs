#!/usr/bin/env node
// `npm start`: installs the npm packages if needed and serves the app with
// Vite's dev server. Open the printed URL in a browser with WebGPU.
import { spawn } from 'node:child_process';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { ensureNodeModules } from './setup/npm-deps.mjs';

const root = fileURLToPath(new URL('..', import.meta.url));
ensureNodeModules(root);
const port = process.env.PORT ?? '5173';
const child = spawn(
  join(root, 'node_modules', '.bin', 'vite'),
  ['--port', port, '--host', process.env.HOST ?? 'localhost', ...process.argv.slice(2)],
  {
    cwd: root,
    stdio: 'inherit',
  },
);
console.log(`\nServing the app at http://${process.env.HOST ?? 'localhost'}:${port}/ (Ctrl+C to stop)\n`);
child.on('exit', (code) => process.exit(code ?? 0));
for (const sig of ['SIGINT', 'SIGTERM']) process.on(sig, () => child.kill(sig));
