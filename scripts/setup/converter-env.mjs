// The converter's Python environment (.venv-converter): converter/requirements.txt
// (pinned; zfpy 1.0.1, which numcodecs imports, unlike the tests' .venv with
// zfpy 1.0.1.post0), plus packages installed without dependencies: ngff-zarr
// (its OME-Zarr schemas, and the test fixtures it writes) and the few of its
// dependencies the converter's do not give (requirements-fixtures.txt).
// Made on first use by `npm run convert`, `npm run bench:convert` and `npm test`.
import { execSync } from 'node:child_process';
import { createHash } from 'node:crypto';
import { existsSync, readFileSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';

const VENV = '.venv-converter';
const FILES = ['converter/requirements.txt', 'converter/requirements-schemas.txt', 'converter/requirements-fixtures.txt'];

export function converterPython(root) {
  return join(root, VENV, 'bin', 'python');
}

/** Environment for running the converter package from the checkout. */
export function converterEnv(root) {
  const path = join(root, 'converter');
  return { ...process.env, PYTHONPATH: process.env.PYTHONPATH ? `${path}:${process.env.PYTHONPATH}` : path };
}

export function ensureConverterEnv(root, log = console.error) {
  const hash = createHash('sha256');
  for (const f of FILES) hash.update(readFileSync(join(root, f)));
  const want = hash.digest('hex');
  const stamp = join(root, VENV, '.install-stamp');
  if (existsSync(stamp) && readFileSync(stamp, 'utf8') === want) return converterPython(root);
  const python = ['python3', 'python'].find((p) => {
    try {
      execSync(`${p} -c "import venv, sys; assert sys.version_info >= (3, 11)"`, { stdio: 'ignore' });
      return true;
    } catch {
      return false;
    }
  });
  if (!python) throw new Error('The converter needs Python 3.11 or newer with venv (Debian: apt-get install python3 python3-venv).');
  if (!existsSync(converterPython(root))) {
    log(`[setup] creating ${VENV} for the converter...`);
    execSync(`${python} -m venv ${VENV}`, { cwd: root, stdio: 'inherit' });
  }
  log(`[setup] installing the converter's dependencies into ${VENV} (pip)...`);
  const pip = `${converterPython(root)} -m pip install -q --disable-pip-version-check`;
  execSync(`${pip} -r ${FILES[0]}`, { cwd: root, stdio: 'inherit' });
  execSync(`${pip} --no-deps -r ${FILES[1]} -r ${FILES[2]}`, { cwd: root, stdio: 'inherit' });
  writeFileSync(stamp, want);
  return converterPython(root);
}
