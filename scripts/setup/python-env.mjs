// A Python virtual environment with the reference tools the tests compare
// against (zfpy, VTK, laspy, tifffile, ...), listed in tests/python-requirements.txt.
import { execSync } from 'node:child_process';
import { createHash } from 'node:crypto';
import { existsSync, readFileSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';

export function venvPython(root) {
  return join(root, '.venv', 'bin', 'python');
}

export function ensurePythonEnv(root) {
  const reqFile = join(root, 'tests', 'python-requirements.txt');
  if (!existsSync(reqFile)) return undefined;
  const want = createHash('sha256').update(readFileSync(reqFile)).digest('hex');
  const stamp = join(root, '.venv', '.install-stamp');
  if (existsSync(stamp) && readFileSync(stamp, 'utf8') === want) return venvPython(root);
  const python = ['python3', 'python'].find((p) => {
    try {
      execSync(`${p} --version`, { stdio: 'ignore' });
      return true;
    } catch {
      return false;
    }
  });
  if (!python) throw new Error('Python 3 is needed for the reference tools (zfpy, vtk): install python3 and python3-venv.');
  if (!existsSync(venvPython(root))) {
    console.error('[setup] creating .venv for the reference tools...');
    execSync(`${python} -m venv .venv`, { cwd: root, stdio: 'inherit' });
  }
  console.error('[setup] installing reference tools into .venv (pip)...');
  execSync(`${venvPython(root)} -m pip install -q --disable-pip-version-check -r tests/python-requirements.txt`, {
    cwd: root,
    stdio: 'inherit',
  });
  writeFileSync(stamp, want);
  return venvPython(root);
}
