// The chunk plan against a brute-force CPU reference computed by NumPy on the
// level as zarr-python + numcodecs.zfpy decode it: (1) the same rule from
// per-chunk min/max taken over the decoded voxels, (2) every chunk that holds
// a corner of a cell that emits triangles (a sign change, VTK's inside rule
// value >= iso) is in the plan, and (3) a narrow surface needs a small part.
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, it } from 'vitest';
import { chunksNeeded, nearestFirst, neighbourhoodOf, neighbourhoodRanges } from '../../../src/store/plan.ts';
import { mulberry32 } from '../../../src/util/random.ts';
import { storeForLocation } from '../../../src/store/zarr/node-store.ts';
import { openStore } from '../../../src/store/zarr/open-store.ts';
import { convert, converterPython } from './stores.ts';

const work = mkdtempSync(join(tmpdir(), 'store-plan-'));
const store = join(work, 'hydrogen.zarr');
const isos = [0.5, 3, 10.25, 40, 90, 200];
let reference: { rule: number[][]; emitting: number[][]; ranges: number[] };

beforeAll(() => {
  convert('volumes/hydrogen_atom_128x128x128_float32.raw', store, ['--chunk', '16', '--rate', '6', '--levels', '2']);
  reference = JSON.parse(
    converterPython(
      `
import sys, json, numpy as np, zarr
v = zarr.open_array(sys.argv[1], mode='r', path='0')[:].astype(np.float64)   # numcodecs.zfpy decode
isos = json.loads(sys.argv[2]); C = 16
nz, ny, nx = v.shape; gz, gy, gx = [-(-n // C) for n in v.shape]
lo = np.full((gz, gy, gx), np.inf); hi = np.full((gz, gy, gx), -np.inf)
for z in range(gz):
  for y in range(gy):
    for x in range(gx):
      b = v[z*C:(z+1)*C, y*C:(y+1)*C, x*C:(x+1)*C]; lo[z, y, x] = b.min(); hi[z, y, x] = b.max()
pad = lambda a, f: np.pad(a, 1, constant_values=f)
L, H = pad(lo, np.inf), pad(hi, -np.inf)
nlo = np.min([L[1+dz:1+dz+gz, 1+dy:1+dy+gy, 1+dx:1+dx+gx] for dz in (-1,0,1) for dy in (-1,0,1) for dx in (-1,0,1)], axis=0)
nhi = np.max([H[1+dz:1+dz+gz, 1+dy:1+dy+gy, 1+dx:1+dx+gx] for dz in (-1,0,1) for dy in (-1,0,1) for dx in (-1,0,1)], axis=0)
corners = [v[dz:nz-1+dz, dy:ny-1+dy, dx:nx-1+dx] for dz in (0,1) for dy in (0,1) for dx in (0,1)]
cmin, cmax = np.min(corners, axis=0), np.max(corners, axis=0)
rule, emitting = [], []
for iso in isos:
  rule.append(np.flatnonzero(((nlo < iso) & (iso <= nhi)).reshape(-1)).tolist())
  cells = (cmin < iso) & (cmax >= iso)
  touched = np.zeros(v.shape, bool)
  for dz in (0,1):
    for dy in (0,1):
      for dx in (0,1): touched[dz:nz-1+dz, dy:ny-1+dy, dx:nx-1+dx] |= cells
  t = np.pad(touched, [(0, gz*C-nz), (0, gy*C-ny), (0, gx*C-nx)]).reshape(gz, C, gy, C, gx, C).any(axis=(1, 3, 5))
  emitting.append(np.flatnonzero(t.reshape(-1)).tolist())
print(json.dumps({'rule': rule, 'emitting': emitting, 'ranges': np.stack([lo, hi], -1).reshape(-1).tolist()}))
`,
      [store, JSON.stringify(isos)],
    ),
  );
}, 900_000);
afterAll(() => rmSync(work, { recursive: true, force: true }));

describe('chunk plan', () => {
  it('equals the brute-force rule, covers every chunk an emitting cell touches, and is narrow for narrow surfaces', async () => {
    const s = await openStore(storeForLocation(store), store);
    const ranges = (await s.readRanges(0))!;
    expect(Array.from(ranges)).toEqual(reference.ranges.map(Math.fround));
    const nb = neighbourhoodRanges(s.levels[0].layout.chunkGrid, ranges);
    const total = s.levels[0].chunkCount;
    isos.forEach((iso, i) => {
      const plan = chunksNeeded(nb, iso);
      expect(plan, `iso ${iso}`).toEqual(reference.rule[i]);
      const planned = new Set(plan);
      expect(
        reference.emitting[i].filter((c) => !planned.has(c)),
        `iso ${iso}`,
      ).toEqual([]);
      expect(reference.emitting[i].length).toBeGreaterThan(0);
    });
    // the hydrogen atom's high isovalues are a small blob around the nucleus
    expect(chunksNeeded(nb, 200).length / total).toBeLessThan(0.1);
  });

  it('unknown ranges (NaN) make a chunk and its neighbours always needed', () => {
    const r = new Float32Array(2 * 27).fill(0);
    r[2 * 13] = NaN;
    r[2 * 13 + 1] = NaN; // the centre of 3x3x3
    expect(chunksNeeded(neighbourhoodRanges([3, 3, 3], r), 5)).toHaveLength(27);
    const ends = new Float32Array(2 * 4).fill(0);
    ends[0] = NaN;
    ends[1] = NaN; // chunk 0 of a 4x1x1 row
    expect(chunksNeeded(neighbourhoodRanges([4, 1, 1], ends), 5)).toEqual([0, 1]);
  });

  it('one chunk read alone (neighbourhoodOf, the learnt ranges) = the whole grid at once, on awkward grids with unknown chunks', () => {
    const random = mulberry32(11);
    for (const grid of [
      [1, 1, 1],
      [5, 1, 1],
      [1, 7, 2],
      [6, 5, 4],
      [9, 3, 8],
    ] as [number, number, number][]) {
      const n = grid[0] * grid[1] * grid[2];
      const r = new Float32Array(2 * n);
      for (let i = 0; i < n; i++) {
        const a = random() * 100;
        r[2 * i] = random() < 0.1 ? NaN : a;
        r[2 * i + 1] = a + random() * 20;
      }
      const all = neighbourhoodRanges(grid, r);
      for (let c = 0; c < n; c++) {
        const [lo, hi] = neighbourhoodOf(grid, r, c);
        expect([lo, hi], `grid ${grid} chunk ${c}`).toEqual([all[2 * c], all[2 * c + 1]]);
      }
    }
  });

  it('orders chunks nearest-first to a point, ties by index', () => {
    const layout = {
      dims: [40, 32, 32] as [number, number, number],
      chunkEdge: 16,
      chunkGrid: [3, 2, 2] as [number, number, number],
      rate: 8,
      chunkBytes: 0,
      name: 't',
    };
    // chunk 2 (x = 32..40) has its centre at x = 36
    expect(nearestFirst(layout, [0, 1, 2, 3, 4, 5], [37, 0, 0])).toEqual([2, 1, 5, 4, 0, 3]);
    expect(nearestFirst(layout, [11, 0, 5], [16, 16, 16])).toEqual([0, 5, 11]);
  });
});
