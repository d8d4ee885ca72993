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
import { cameraForBox, cameraFromView, fitBox0, sceneRadiusOf } from '../../../src/store/view/camera.ts';
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
 * Seams of a mixed surface: its edges with one triangle away from the
 * volume's faces (a single level has none; the coarsest level here sits 3.5
 * voxels inside them), and for each, how far its midpoint is from the
 * nearest triangle of another piece of the surface (another connected
 * component: another level) away from that piece's own open edges (capped
 * at 3 voxels): what the crack leaves uncovered. Skirts overlap the
 * neighbouring region by one cell, so the open edges stay but lie over the
 * other level's surface.
 */
function seams(ply: string): { open: number; medianGap: number; p95Gap: number; over1: number; over2: number } {
  return JSON.parse(
    runPython(
      `
import sys, json, numpy as np
def read(path):
    b = open(path, 'rb').read()
    head = b[:b.index(b'end_header\\n') + 11].decode()
    nv = int(head.split('element vertex ')[1].split()[0]); nf = int(head.split('element face ')[1].split()[0])
    body = b[len(head):]
    v = np.frombuffer(body[:nv * 12], np.float32).reshape(nv, 3)
    f = np.frombuffer(body[nv * 12:], dtype=np.dtype([('n', 'u1'), ('i', '<u4', 3)]), count=nf)['i']
    return v, f
def seg_dist(p, a, b, c):
    # closest point on triangles (a,b,c) to p (vectorized over triangles), Ericson's method
    ab = b - a; ac = c - a; ap = p - a
    d1 = (ab * ap).sum(1); d2 = (ac * ap).sum(1)
    bp = p - b; d3 = (ab * bp).sum(1); d4 = (ac * bp).sum(1)
    cp = p - c; d5 = (ab * cp).sum(1); d6 = (ac * cp).sum(1)
    va = d3 * d6 - d5 * d4; vb = d5 * d2 - d1 * d6; vc = d1 * d4 - d3 * d2
    denom = va + vb + vc
    denom = np.where(np.abs(denom) < 1e-30, 1e-30, denom)
    v = vb / denom; w = vc / denom
    q = a + ab * v[:, None] + ac * w[:, None]
    # fall back to edges/vertices where outside
    out = (va < 0) | (vb < 0) | (vc < 0)
    if out.any():
        def on_seg(x, y):
            d = y - x; t = np.clip(((p - x) * d).sum(1) / np.maximum((d * d).sum(1), 1e-30), 0, 1)
            return x + d * t[:, None]
        cands = np.stack([on_seg(a, b), on_seg(b, c), on_seg(c, a)])
        dd = ((cands - p) ** 2).sum(2)
        best = cands[dd.argmin(0), np.arange(len(p))]
        q = np.where(out[:, None], best, q)
    return np.sqrt(((q - p) ** 2).sum(1))
v, f = read(sys.argv[1])
points, ids = np.unique(v, axis=0, return_inverse=True)
t = ids.reshape(-1)[f]
# components (union-find over welded vertices)
parent = np.arange(len(points))
def find(x):
    r = x
    while parent[r] != r: r = parent[r]
    while parent[x] != r: parent[x], x = r, parent[x]
    return r
for a, b, c in t:
    ra, rb, rc = find(a), find(b), find(c)
    parent[rb] = ra; parent[find(rc)] = ra
comp = np.array([find(i) for i in range(len(points))])
tcomp = comp[t[:, 0]]
e = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]); e.sort(axis=1)
u, inv, counts = np.unique(e, axis=0, return_inverse=True, return_counts=True)
o = u[counts == 1]
# triangles with an open edge: the boundary strip of each piece (coverage is measured away from it)
nt = len(t)
edge_open = (counts == 1)[inv.reshape(-1)]
boundary = edge_open.reshape(3, nt).any(0)
p = points.astype(np.float64)
face = lambda q: ((q <= 3.5) | (q >= 251.5)).any(axis=1)
o = o[~(face(p[o[:, 0]]) & face(p[o[:, 1]]))]
mid = (p[o[:, 0]] + p[o[:, 1]]) / 2
ocomp = comp[o[:, 0]]
tri = p[t]
cent = tri.mean(1)
R = 3.0
cell = np.floor(cent / R).astype(np.int64)
from collections import defaultdict
buckets = defaultdict(list)
for i, k in enumerate(map(tuple, cell)): buckets[k].append(i)
gaps = []
for m, c in zip(mid, ocomp):
    k = np.floor(m / R).astype(np.int64)
    cand = [i for dx in (-1, 0, 1) for dy in (-1, 0, 1) for dz in (-1, 0, 1) for i in buckets.get((k[0] + dx, k[1] + dy, k[2] + dz), [])]
    cand = np.array([i for i in cand if tcomp[i] != c and not boundary[i]], dtype=np.int64)
    if len(cand) == 0:
        gaps.append(R); continue
    d = seg_dist(np.repeat(m[None], len(cand), 0), tri[cand, 0], tri[cand, 1], tri[cand, 2])
    gaps.append(min(float(d.min()), R))
g = np.array(gaps) if gaps else np.zeros(1)
print(json.dumps({'open': int(len(o)), 'medianGap': float(np.median(g)), 'p95Gap': float(np.percentile(g, 95)), 'over1': int((g > 1).sum()), 'over2': int((g > 2).sum())}))
`,
      [ply],
    ),
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
    const budgetMb = 23;
    expect(levelPeak).toBeGreaterThan(3 * budgetMb * 2 ** 20); // level 0 alone does not fit
    const r = extract('--view-box', BOX, '--cache-budget', String(budgetMb), '--ply', join(work, 'view'));
    const surface = r.isosurfaces[0];
    const cut: CutEntry[] = surface.cut;
    // the corner at full resolution, coarser levels elsewhere
    expect(cut.some((e) => e.level === 0 && e.chunk.every((c) => c === 7))).toBe(true);
    expect(new Set(cut.map((e) => e.level)).size).toBeGreaterThan(1);
    // the cut's triangles are the surface's, besides the skirts' (counted apart)
    const cutTriangles = cut.reduce((a, e) => a + e.triangles, 0);
    expect(surface.stitchTriangles).toBe(surface.triangles - cutTriangles);
    expect(surface.stitchTriangles).toBeGreaterThan(0);
    // within the budget, a fraction of level 0 fetched
    expect(r.store.gpuPeakBytes).toBeLessThanOrEqual(budgetMb * 2 ** 20);
    expect(surface.gpuBytes).toBeLessThanOrEqual(budgetMb * 2 ** 20);
    expect(r.store.chunkBytesFetched).toBeLessThan(0.5 * whole.store.chunkBytesFetched);
    // each chunk: its level's regular cells, as VTK counts them
    const vtk = vtkCounts(cut);
    const mismatches = cut.map((e, i) => ({ ...e, vtk: vtk[i] })).filter((e) => e.triangles !== e.vtk);
    expect(mismatches).toEqual([]);
    expect(cut.filter((e) => e.triangles > 0).length).toBeGreaterThan(20);
    // seams against the level-0 surface, with skirts and without
    const withSkirts = seams(surface.ply);
    const bare = extract('--view-box', BOX, '--cache-budget', String(budgetMb), '--no-skirts', '--ply', join(work, 'bare'));
    expect(bare.isosurfaces[0].stitchTriangles).toBe(0);
    expect(bare.isosurfaces[0].cut).toEqual(cut);
    const without = seams(bare.isosurfaces[0].ply);
    expect(seams(whole.isosurfaces[0].ply).open).toBe(0);
    expect(withSkirts.over1).toBeLessThan(without.over1);
    console.log(
      `view cut: ${cut.length} chunks (${[0, 1, 2, 3].map((L) => `level ${L}: ${cut.filter((e) => e.level === L).length}`).join(', ')}), ` +
        `${surface.triangles} triangles (level 0 whole: ${whole.isosurfaces[0].triangles}); GPU peak ${(r.store.gpuPeakBytes / 2 ** 20).toFixed(1)} MiB ` +
        `(level 0 whole: ${(levelPeak / 2 ** 20).toFixed(1)} MiB); fetched ${(r.store.chunkBytesFetched / 2 ** 20).toFixed(2)} of ${(whole.store.chunkBytesFetched / 2 ** 20).toFixed(2)} MiB; ` +
        `stitching (skirt) triangles ${surface.stitchTriangles}; seams (one-triangle edges inside the volume; the gap each leaves to another level's surface, voxels): ` +
        `with skirts ${withSkirts.open}, median ${withSkirts.medianGap.toFixed(2)}, p95 ${withSkirts.p95Gap.toFixed(2)}, ${withSkirts.over1} over 1, ${withSkirts.over2} over 2; ` +
        `without ${without.open}, median ${without.medianGap.toFixed(2)}, p95 ${without.p95Gap.toFixed(2)}, ${without.over1} over 1, ${without.over2} over 2`,
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
