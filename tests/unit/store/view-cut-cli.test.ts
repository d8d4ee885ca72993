// The view's mixed-level surface, headless (`extract STORE --view-box` /
// `--view`, src/store/view/): zoomed into a corner of a generated store
// whose level 0 needs about three times the GPU budget, the corner is drawn
// at level 0 and the rest coarser, within the budget, fetching a fraction of
// level 0. Truth from outside: per chunk of the cut, its triangles equal
// vtkMarchingCubes' count over that chunk's cells at its level (the chunk
// plus one voxel on its upper faces, decoded by zarr-python + zfpy): so
// every drawn chunk's cells are the level's regular cells, none missing or
// doubled where levels meet. The seams between levels are measured (edges
// with one triangle) and reported.
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, it } from 'vitest';
import { cameraForBox, cameraFromView, fitBox0, sceneRadiusOf } from '../../../src/store/view/cut.ts';
import { DEFAULT_VIEWPORT } from '../../../src/store/view/view-request.ts';
import { storeForLocation } from '../../../src/store/zarr/node-store.ts';
import { openStore } from '../../../src/store/zarr/open-store.ts';
import { runPython } from '../../helpers/python.ts';
import { cli, convert, converterPython } from './stores.ts';

const work = mkdtempSync(join(tmpdir(), 'view-cut-cli-'));
const store = join(work, 'gen256.zarr');
// not a round number: a voxel exactly at the isovalue makes degenerate triangles, which VTK drops
const ISO = 0.437;
const CHUNK = 32;
// the far corner of the volume, seen from outside it (the Fit direction looks from +x, +y, +z)
const BOX = '207,207,207,255,255,255';
beforeAll(() => {
  convert('gen:256x256x256', store, ['--chunk', String(CHUNK), '--rate', '8', '--levels', '4']);
}, 900_000);
afterAll(() => rmSync(work, { recursive: true, force: true }));

interface CutEntry {
  level: number;
  chunk: [number, number, number];
  triangles: number;
}

function extract(...args: string[]) {
  const json = join(work, `out-${Math.random().toString(36).slice(2)}.json`);
  const r = cli('extract', store, '--iso', String(ISO), '--json', json, ...args);
  expect(r.status, r.stderr).toBe(0);
  return JSON.parse(readFileSync(json, 'utf8'));
}

/** vtkMarchingCubes' triangles over each entry's cells, from zarr-python's decode of its level. */
function vtkCounts(entries: CutEntry[]): number[] {
  const dir = mkdtempSync(join(work, 'regions-'));
  converterPython(
    `
import sys, json, numpy as np, zarr
store, C, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
entries = json.loads(sys.argv[4])
arrays = {}
shapes = []
for i, e in enumerate(entries):
    L = e['level']
    if L not in arrays: arrays[L] = zarr.open_array(store, path=str(L), mode='r')
    a = arrays[L]
    x, y, z = (c * C for c in e['chunk'])
    part = np.ascontiguousarray(a[z:z + C + 1, y:y + C + 1, x:x + C + 1], dtype=np.float32)
    part.tofile(f'{out}/{i}.f32')
    shapes.append(list(part.shape))
open(f'{out}/shapes.json', 'w').write(json.dumps(shapes))
`,
    [store, String(CHUNK), dir, JSON.stringify(entries)],
  );
  return JSON.parse(
    runPython(
      `
import sys, json, numpy as np, vtk
from vtk.util.numpy_support import numpy_to_vtk
out, iso = sys.argv[1], float(np.float32(float(sys.argv[2])))
shapes = json.load(open(f'{out}/shapes.json'))
counts = []
for i, (nz, ny, nx) in enumerate(shapes):
    if min(nz, ny, nx) < 2:
        counts.append(0)
        continue
    img = vtk.vtkImageData(); img.SetDimensions(nx, ny, nz)
    img.GetPointData().SetScalars(numpy_to_vtk(np.fromfile(f'{out}/{i}.f32', np.float32), deep=1))
    mc = vtk.vtkMarchingCubes(); mc.SetInputData(img); mc.SetValue(0, iso); mc.ComputeNormalsOff(); mc.Update()
    counts.append(mc.GetOutput().GetNumberOfPolys())
print(json.dumps(counts))
`,
      [dir, String(ISO)],
    ),
  );
}

/**
 * Edges used by exactly one triangle (positions compared exactly) that do not
 * lie on the volume's faces (0 or 255 on an axis): the openings of a surface
 * inside the volume (a single level's has none; a mixed one's are its seams).
 */
function boundaryEdges(ply: string): number {
  return Number(
    runPython(
      `
import sys, numpy as np
b = open(sys.argv[1], 'rb').read()
head = b[:b.index(b'end_header\\n') + 11].decode()
nv = int(head.split('element vertex ')[1].split()[0]); nf = int(head.split('element face ')[1].split()[0])
body = b[len(head):]
props = head.split('element face')[0].count('property float')
v = np.frombuffer(body[:nv * 4 * props], np.float32).reshape(nv, props)[:, :3]
f = np.frombuffer(body[nv * 4 * props:], dtype=np.dtype([('n', 'u1'), ('i', '<u4', 3)]), count=nf)['i']
points, ids = np.unique(v, axis=0, return_inverse=True)
ids = ids.reshape(-1)
t = ids[f]
e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
e.sort(axis=1)
u, counts = np.unique(e, axis=0, return_counts=True)
open_ = u[counts == 1]
p = points.astype(np.float64)
def on_face(i):
    q = p[i]
    return ((q <= 0) | (q >= 255)).any(axis=1)
inner = ~(on_face(open_[:, 0]) & on_face(open_[:, 1]))
print(int(inner.sum()))
`,
      [ply],
    ).trim(),
  );
}

describe('extract STORE --view-box: one surface from several levels', () => {
  it("levels are placed by their OME translation: the converter's (2^L - 1) / 2 level-0 voxels", async () => {
    const s = await openStore(storeForLocation(store), store);
    expect(s.levelOffsets).toEqual([0, 0.5, 1.5, 3.5].map((o) => [o, o, o]));
  });

  it('zoomed into a corner within a budget a third of level 0: level 0 there, every chunk of the cut = VTK over its cells, within the budget', () => {
    const whole = extract('--level', '0', '--cache-budget', '512', '--ply', join(work, 'level0'));
    const levelPeak = whole.store.gpuPeakBytes;
    const budgetMb = 24;
    expect(levelPeak).toBeGreaterThan(3 * budgetMb * 2 ** 20); // level 0 alone does not fit
    const r = extract('--view-box', BOX, '--cache-budget', String(budgetMb), '--ply', join(work, 'view'));
    const surface = r.isosurfaces[0];
    const cut: CutEntry[] = surface.cut;
    // the corner at full resolution, coarser levels elsewhere
    expect(cut.some((e) => e.level === 0 && e.chunk.every((c) => c === 7))).toBe(true);
    expect(new Set(cut.map((e) => e.level)).size).toBeGreaterThan(1);
    // the cut's triangles are the surface's
    expect(cut.reduce((a, e) => a + e.triangles, 0)).toBe(surface.triangles);
    // within the budget, a fraction of level 0 fetched
    expect(r.store.gpuPeakBytes).toBeLessThanOrEqual(budgetMb * 2 ** 20);
    expect(surface.gpuBytes).toBeLessThanOrEqual(budgetMb * 2 ** 20);
    expect(r.store.chunkBytesFetched).toBeLessThan(0.5 * whole.store.chunkBytesFetched);
    // each chunk: its level's regular cells, as VTK counts them
    const vtk = vtkCounts(cut);
    const mismatches = cut.map((e, i) => ({ ...e, vtk: vtk[i] })).filter((e) => e.triangles !== e.vtk);
    expect(mismatches).toEqual([]);
    expect(cut.filter((e) => e.triangles > 0).length).toBeGreaterThan(20);
    // seams: edges with one triangle inside the volume, against the single-level surface's (none)
    const seams = boundaryEdges(surface.ply);
    const single = boundaryEdges(whole.isosurfaces[0].ply);
    expect(single).toBe(0);
    console.log(
      `view cut: ${cut.length} chunks (${[0, 1, 2, 3].map((L) => `level ${L}: ${cut.filter((e) => e.level === L).length}`).join(', ')}), ` +
        `${surface.triangles} triangles (level 0 whole: ${whole.isosurfaces[0].triangles}); GPU peak ${(r.store.gpuPeakBytes / 2 ** 20).toFixed(1)} MiB ` +
        `(level 0 whole: ${(levelPeak / 2 ** 20).toFixed(1)} MiB); fetched ${(r.store.chunkBytesFetched / 2 ** 20).toFixed(2)} of ${(whole.store.chunkBytesFetched / 2 ** 20).toFixed(2)} MiB; ` +
        `one-triangle edges inside the volume (seams) ${seams} (level 0 whole: ${single})`,
    );
  }, 600_000);

  it("--view with the page's link of the same camera gives the same cut as --view-box", () => {
    const cam = cameraFromView(
      cameraForBox([207, 207, 207, 255, 255, 255], [1, 1, 1], DEFAULT_VIEWPORT).state,
      DEFAULT_VIEWPORT,
      sceneRadiusOf(fitBox0({ dims: [256, 256, 256] }, 0), [1, 1, 1]),
    );
    const s = cam.state;
    const link = `#iso=${ISO}&cam=${[...s.rotation, ...s.target, s.distance].join(',')}&px=${DEFAULT_VIEWPORT.width},${DEFAULT_VIEWPORT.height}&tol=1.5`;
    const a = extract('--view-box', BOX);
    const b = extract('--view', link);
    expect(b.isosurfaces[0].cut).toEqual(a.isosurfaces[0].cut);
    // a coarser tolerance draws coarser
    const c = extract('--view-box', BOX, '--tolerance', '6');
    const finest = (cut: CutEntry[]) => cut.filter((e) => e.level === 0).length;
    expect(finest(c.isosurfaces[0].cut)).toBeLessThan(finest(a.isosurfaces[0].cut));
    // usage errors
    expect(cli('extract', store, '--iso', String(ISO), '--view-box', '1,2,3').status).toBe(2);
    expect(cli('extract', store, '--iso', String(ISO), '--view', '#iso=1').status).toBe(2);
    expect(cli('extract', store, '--iso', String(ISO), '--view-box', BOX, '--level', '0').status).toBe(2);
  }, 600_000);
});
