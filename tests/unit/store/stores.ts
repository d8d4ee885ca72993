// Test stores: made by the converter (scripts/convert.mjs, as `npm run
// convert` does) and by zarr-python + numcodecs directly ("stores written by
// others": no range arrays, no zfpzarr attributes), in a temporary folder.
import { execFileSync, spawnSync } from 'node:child_process';
import { join } from 'node:path';
import { repoRoot, runPython, sharedData } from '../../helpers/python.ts';

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

/** Whether two PLY files hold the same triangles (each a set of three vertex positions), by NumPy. */
export function samePly(a: string, b: string): string {
  return runPython(
    `
import sys, numpy as np
from ply import read_ply
def tris(path):
    v, f = read_ply(path)
    nf = f.shape[0]
    t = v[f]                                        # nf x 3 x 3
    t = t.view([('x', '<f4'), ('y', '<f4'), ('z', '<f4')]).reshape(nf, 3)
    t = np.sort(t, axis=1)                          # the three corners in one order
    return np.sort(t.view('V36').reshape(nf))       # the triangles in one order
ta, tb = tris(sys.argv[1]), tris(sys.argv[2])
print('same' if ta.shape == tb.shape and (ta == tb).all() else f'differ: {ta.shape[0]} vs {tb.shape[0]} triangles, {int((ta != tb).sum()) if ta.shape == tb.shape else -1} differ')
`,
    [a, b],
  ).trim();
}

/** Runs the CLI (src/cli/main.ts) as a user would; its exit status and output. */
export function cli(...args: string[]): { status: number | null; stderr: string; stdout: string } {
  const r = spawnSync(
    process.execPath,
    ['--import', join(repoRoot, 'scripts/register-node-loaders.mjs'), join(repoRoot, 'src/cli/main.ts'), ...args],
    { encoding: 'utf8', timeout: 600_000 },
  );
  return { status: r.status, stderr: r.stderr, stdout: r.stdout };
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

export interface SparseStoreSpec {
  /** Level-0 voxels per axis (x = y = z), unless `shape` says otherwise. */
  size: number;
  /** Level-0 voxels along x, y, z when they differ (`size` is then unused). */
  shape?: [number, number, number];
  chunk: number;
  rate: number;
  levels: number;
  /** Chunks per axis of the data box, at the far corner of level 0; everything else is absent (fill value 0). */
  boxChunks: number;
}

/**
 * A store laid out as the converter lays it out (OME-Zarr 0.5 group, zfpy
 * levels, ranges/<L>, zfpzarr attributes), sparse: level 0 holds, in a box of
 * chunks at its far corner, the field max(0, 100 - distance to the box's
 * centre); every other chunk is absent, so it reads as the fill value 0 (the
 * range arrays' fill value is 0 too: their absent entries say [0, 0]). A
 * coarser level holds the same field sampled at its voxel centres. The
 * written chunks' ranges come from zarr-python's decode of them. Quick to
 * make at any size: only the box is written.
 */
export function sparseStore(out: string, spec: SparseStoreSpec): string {
  converterPython(
    `
import sys, json, math, numpy as np, zarr
sys.path.insert(0, sys.argv[3])
from zarr.codecs.numcodecs import ZFPY
from zfpzarr.store import ome_multiscales, ATTR, FORMAT_VERSION
out, spec = sys.argv[1], json.loads(sys.argv[2])
C, levels = spec['chunk'], spec['levels']
S0 = spec.get('shape') or [spec['size']] * 3   # x, y, z
S0 = S0[::-1]                                  # z, y, x: the arrays' order
box = spec['boxChunks'] * C
centre = [max(0, n - box) + min(n, box) / 2 for n in S0]
shapes = [tuple(-(-n // 2**L) for n in S0) for L in range(levels)]
attrs = {'ome': ome_multiscales('sparse', shapes, None, None),
         ATTR: {'format': FORMAT_VERSION, 'complete': True, 'value_range': [0.0, 100.0],
                'levels': [{'path': str(L), 'ranges': f'ranges/{L}'} for L in range(levels)]}}
g = zarr.create_group(store=out, zarr_format=3, attributes=attrs, overwrite=True)
for L, shape in enumerate(shapes):
    a = g.create_array(name=str(L), shape=shape, chunks=(C,) * 3, dtype='float32',
                       serializer=ZFPY(mode=2, rate=spec['rate']), compressors=None, filters=None, fill_value=0.0,
                       dimension_names=['z', 'y', 'x'])
    grid = tuple(-(-n // C) for n in shape)
    r = g.create_array(name=f'ranges/{L}', shape=(*grid, 2), chunks=(*(min(n, 64) for n in grid), 2), dtype='float32',
                       compressors=None, filters=None, fill_value=0.0, dimension_names=['z', 'y', 'x', 'minmax'])
    f = 2**L
    lo = [int(max(0, n - box) // f) for n in S0]
    idx = [(np.arange(l, m, dtype=np.float64) + 0.5) * f - 0.5 for l, m in zip(lo, shape)]
    zz, yy, xx = np.meshgrid(*idx, indexing='ij')
    field = np.maximum(0.0, 100.0 - np.sqrt((xx - centre[2]) ** 2 + (yy - centre[1]) ** 2 + (zz - centre[0]) ** 2)).astype(np.float32)
    a[lo[0]:, lo[1]:, lo[2]:] = field
    c0 = [l // C for l in lo]
    for cz in range(c0[0], grid[0]):
        for cy in range(c0[1], grid[1]):
            for cx in range(c0[2], grid[2]):
                part = a[cz * C:(cz + 1) * C, cy * C:(cy + 1) * C, cx * C:(cx + 1) * C]
                r[cz, cy, cx] = [float(part.min()), float(part.max())]
`,
    [out, JSON.stringify(spec), join(repoRoot, 'converter')],
  );
  return out;
}

/** The level-0 region [lo, size) per axis of a store, decoded by zarr-python, written as raw float32 (x fastest) to `raw`. */
export function decodeRegion(store: string, lo: number | [number, number, number], raw: string): void {
  const [x, y, z] = typeof lo === 'number' ? [lo, lo, lo] : lo;
  converterPython(
    `
import sys, numpy as np, zarr
a = zarr.open_array(sys.argv[1], path='0', mode='r')
x, y, z = map(int, sys.argv[2:5])
np.ascontiguousarray(a[z:, y:, x:], dtype=np.float32).tofile(sys.argv[5])
`,
    [store, String(x), String(y), String(z), raw],
  );
}
