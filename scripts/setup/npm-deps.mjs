// Installs the npm dependencies when node_modules is missing or older than
// package-lock.json / package.json, so `npm start` and `npm test` work on a
// fresh clone with only Node and npm.
import { execSync } from 'node:child_process';
import { existsSync, readFileSync, statSync, writeFileSync } from 'node:fs';
import { createHash } from 'node:crypto';
import { join } from 'node:path';

function manifestHash(root) {
  const h = createHash('sha256');
  for (const f of ['package.json', 'package-lock.json']) {
    const p = join(root, f);
    if (existsSync(p)) h.update(readFileSync(p));
  }
  return h.digest('hex');
}

export function ensureNodeModules(root, { quiet = false } = {}) {
  const stamp = join(root, 'node_modules', '.install-stamp');
  const want = manifestHash(root);
  if (existsSync(stamp) && readFileSync(stamp, 'utf8') === want) return false;
  // A fresh clone gets exactly the lock file; an existing tree is updated in
  // place (npm ci would delete node_modules under anything else running).
  const fresh = !existsSync(join(root, 'node_modules'));
  const hasLock = existsSync(join(root, 'package-lock.json'));
  const cmd = fresh && hasLock ? 'npm ci --no-audit --no-fund' : 'npm install --no-audit --no-fund';
  if (!quiet || !existsSync(join(root, 'node_modules'))) console.error(`[setup] installing npm packages (${cmd})...`);
  execSync(cmd, { cwd: root, stdio: quiet ? ['ignore', 'ignore', 'inherit'] : 'inherit' });
  writeFileSync(stamp, want);
  return true;
}

export function isFile(p) {
  try {
    return statSync(p).isFile();
  } catch {
    return false;
  }
}
