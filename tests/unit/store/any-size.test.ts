// Any size: GPU state follows what is resident, not the level. Sparse stores
// (stores.ts sparseStore: a field in a box of chunks at the far corner of
// level 0, every other chunk absent, reading as the fill value) of 2048^3,
// 4096^3 and 16384^3 voxels (the last: 2^36 blocks, 2^45 bits of level 0,
// 2^24 chunks) on a device with WebGPU's default limits, within 256 MB:
// - the triangles at level 0 equal vtkMarchingCubes' over the chunks the
//   surface touches (plus one voxel on their upper faces), decoded by
//   zarr-python; the vertices lie in the box at the far corner (block
//   coordinates past 2^32 block ids placed right);
// - the GPU bytes after opening differ between the three only by the level's
//   tables, 8 bytes per chunk of the level: the same chunks resident give the
//   same bytes whatever the level's block count.
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, it } from 'vitest';
import type { GpuFailure } from '../../../src/gpu/device.ts';
import { requestNodeGpu } from '../../../src/gpu/node-gpu.ts';
import { meshPositions } from '../../../src/isosurface/vertex-format.ts';
import { openStoreInput } from '../../../src/store/cli-input.ts';
import { zfpChunkBytes } from '../../../src/store/zarr/open-store.ts';
import { countBuffers } from '../../helpers/gpu-memory.ts';
import { finishTestGpu, pushTestScopes } from '../../helpers/gpu-scopes.ts';
import type { StoreStreamSurface } from '../../../src/store/stream-surface.ts';
import { runPython } from '../../helpers/python.ts';
import { decodeRegion, sparseStore } from './stores.ts';

const work = mkdtempSync(join(tmpdir(), 'store-any-size-'));
const MiB = 2 ** 20;
const CHUNK = 64;
const BOX_CHUNKS = 3;
// Not a value the field takes exactly: where a voxel equals the isovalue, vtkMarchingCubes merges the
// vertices that meet there and drops the triangles that become degenerate; ours keeps one vertex per edge.
const ISO = 50.37;
const sizes = [2048, 4096, 16384];
const path = (size: number) => join(work, `sparse${size}.zarr`);

// 40000 voxels along x (past 16384, where a vertex's 12-bit block coordinates once ended), the box at the far end
const WIDE: [number, number, number] = [40000, 2 * CHUNK, 2 * CHUNK];
const widePath = join(work, 'sparse-wide.zarr');

beforeAll(() => {
  for (const size of sizes) sparseStore(path(size), { size, chunk: CHUNK, rate: 8, levels: 2, boxChunks: BOX_CHUNKS });
  sparseStore(widePath, { size: 0, shape: WIDE, chunk: CHUNK, rate: 8, levels: 2, boxChunks: 2 });
}, 900_000);
afterAll(() => rmSync(work, { recursive: true, force: true }));

/** vtkMarchingCubes' triangle count over a raw float32 cube of n^3 voxels. */
function vtkTriangles(raw: string, n: number, iso: number): number {
  return Number(
    runPython(
      `
import sys, numpy as np, vtk
from vtk.util.numpy_support import numpy_to_vtk
n = int(sys.argv[2])
a = np.fromfile(sys.argv[1], np.float32)
img = vtk.vtkImageData()
img.SetDimensions(n, n, n)
img.GetPointData().SetScalars(numpy_to_vtk(a, deep=1))
mc = vtk.vtkMarchingCubes()
mc.SetInputData(img)
mc.SetValue(0, float(np.float32(float(sys.argv[3]))))
mc.ComputeNormalsOff()
mc.Update()
print(mc.GetOutput().GetNumberOfPolys())
`,
      [raw, String(n), String(iso)],
    ).trim(),
  );
}

describe('a level of any size, on the GPU by what is resident', () => {
  it('sparse 2048^3, 4096^3 and 16384^3 levels on default limits within 256 MB: VTK triangles, far-corner blocks right, bytes by chunk count', async () => {
    const failures: GpuFailure[] = [];
    const ctx = await requestNodeGpu({ label: 'test.anySize', limits: 'default', onFailure: (f) => failures.push(f) });
    expect(ctx.limits.maxStorageBufferBindingSize).toBeLessThanOrEqual(128 * MiB);
    pushTestScopes(ctx.device);
    const gpu = { ...ctx, failures };
    const count = countBuffers(gpu.device);
    const after: number[] = [];
    let triangles = -1;
    try {
      for (const size of sizes) {
        const before = count.live;
        const input = await openStoreInput(gpu, path(size), { level: 0, budget: 256 * MiB });
        const stats = await input.surface.compute(ISO);
        const r = input.record();
        expect(r.gpuBytes).toBe(count.live - before);
        // only the box's chunks came over; the absent ones around it read as the fill value, nothing fetched
        expect(r.chunks).toBe(BOX_CHUNKS ** 3);
        expect(r.chunkBytesFetched).toBe(BOX_CHUNKS ** 3 * zfpChunkBytes(CHUNK, 8));
        expect(count.peak - before).toBeLessThanOrEqual(256 * MiB);
        after.push(r.gpuBytes);
        // every vertex in the box at the far corner
        const mesh = await (input.surface as StoreStreamSurface).stream.shown!.levels[0].surface.readMesh();
        const p = meshPositions(mesh);
        let lo = Infinity;
        let hi = -Infinity;
        for (const v of p) {
          lo = Math.min(lo, v);
          hi = Math.max(hi, v);
        }
        expect(lo).toBeGreaterThan(size - BOX_CHUNKS * CHUNK);
        expect(hi).toBeLessThan(size);
        if (triangles < 0) {
          // the chunks the surface touches are the box; plus one voxel on their upper faces (the volume ends there)
          const raw = join(work, `box${size}.raw`);
          decodeRegion(path(size), size - BOX_CHUNKS * CHUNK, raw);
          triangles = vtkTriangles(raw, BOX_CHUNKS * CHUNK, ISO);
          expect(triangles).toBeGreaterThan(10_000);
        }
        expect(stats.triangles, `${size}^3`).toBe(triangles);
        input.surface.destroy();
        expect(count.live).toBe(before);
      }
      // the same resident chunks: only the level's tables (chunk -> slot, slot -> chunk: 8 B per chunk) tell the levels apart
      const chunks = sizes.map((s) => (s / CHUNK) ** 3);
      console.log(`GPU bytes after the surface: ${sizes.map((s, i) => `${s}^3 ${(after[i] / MiB).toFixed(2)} MiB`).join(', ')}`);
      for (let i = 1; i < sizes.length; i++) expect(after[i] - after[0]).toBe(8 * (chunks[i] - chunks[0]));
    } finally {
      count.restore();
      await finishTestGpu(gpu);
    }
  }, 900_000);

  it('a level 40000 voxels wide: VTK triangles over the box at its far end, every vertex placed there', async () => {
    const failures: GpuFailure[] = [];
    const ctx = await requestNodeGpu({ label: 'test.anySize.wide', limits: 'default', onFailure: (f) => failures.push(f) });
    pushTestScopes(ctx.device);
    const gpu = { ...ctx, failures };
    try {
      const input = await openStoreInput(gpu, widePath, { level: 0, budget: 256 * MiB });
      const stats = await input.surface.compute(ISO);
      const p = meshPositions(await (input.surface as StoreStreamSurface).stream.shown!.levels[0].surface.readMesh());
      const box = 2 * CHUNK;
      for (let a = 0; a < 3; a++) {
        let [lo, hi] = [Infinity, -Infinity];
        for (let i = a; i < p.length; i += 3) [lo, hi] = [Math.min(lo, p[i]), Math.max(hi, p[i])];
        expect(lo, `axis ${a}`).toBeGreaterThan(WIDE[a] - box);
        expect(hi, `axis ${a}`).toBeLessThan(WIDE[a]);
      }
      const raw = join(work, 'box-wide.raw');
      decodeRegion(widePath, [WIDE[0] - box, 0, 0], raw);
      const triangles = vtkTriangles(raw, box, ISO);
      expect(triangles).toBeGreaterThan(10_000);
      expect(stats.triangles).toBe(triangles);
      input.surface.destroy();
    } finally {
      await finishTestGpu(gpu);
    }
  }, 600_000);
});
