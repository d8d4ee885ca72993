// Test stores: made by the converter (scripts/convert.mjs, as `npm run
// convert` does) and by zarr-python + numcodecs directly ("stores written by
// others": no range arrays, no zfpzarr attributes), in a temporary folder.
import { execFileSync } from 'node:child_process';
import { join } from 'node:path';
import { repoRoot, sharedData } from '../../helpers/python.ts';

export function convert(input: string, out: string, args: string[]): string {
  execFileSync(
    process.execPath,
    [join(repoRoot, 'scripts/convert.mjs'), input.startsWith('gen:') ? input : join(sharedData, input), '--out', out, '--quiet', ...args],
    {
      cwd: repoRoot,
      stdio: 'pipe',
      timeout: 900_000,
    },
  );
  return out;
}

/** Runs Python in the converter's environment (zarr-python, numcodecs, zfpy). */
export function converterPython(code: string, args: string[] = []): string {
  return execFileSync(join(repoRoot, '.venv-converter/bin/python'), ['-c', code, ...args], { encoding: 'utf8', timeout: 300_000 });
}

/** A float32 array written by zarr-python with the given serializer / compressor (Python source). */
export function zarrPythonStore(
  out: string,
  shape: [number, number, number],
  chunk: number,
  serializer: string,
  dtype = 'float32',
): string {
  converterPython(
    `
import sys, numpy as np, zarr
from numcodecs.zarr3 import ZFPY
z, y, x = ${JSON.stringify(shape)}
g = np.mgrid[0:z, 0:y, 0:x].astype('float64')
v = (np.sin(g[2] / 5) + np.cos(g[1] / 7) + g[0] / z).astype('${dtype}')
a = zarr.create_array(sys.argv[1], shape=v.shape, chunks=(${chunk},) * 3, dtype='${dtype}', ${serializer}, overwrite=True)
a[:] = v
`,
    [out],
  );
  return out;
}
