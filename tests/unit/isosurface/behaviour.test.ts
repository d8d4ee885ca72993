// Isosurface object behaviour: newest isovalue wins (a bounded number of
// computations in flight, a pending one replaced), the memory budget (a refused surface
// leaves the previous one drawn, a clear error; raising the budget lets it
// grow), growth of the vertex output alone (the cache update of the failed
// attempt counts), and destroy().
import { describe, expect } from 'vitest';
import { Isosurface } from '../../../src/isosurface/isosurface.ts';
import { formatMB } from '../../../src/isosurface/budget.ts';
import { IsosurfaceBudgetError, IsosurfaceSupersededError, type IsosurfaceStats } from '../../../src/isosurface/types.ts';
import { marchingCubes } from '../../../src/mc/serial-mc.ts';
import type { Dims } from '../../../src/core/naming.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { compressVolume, decodeVolume, makeField } from './helpers.ts';
import { crossedEdges } from './soup-compare.ts';
import { readVertices } from '../../helpers/isosurface-readback.ts';

const dims: Dims = [30, 27, 22];

async function setup(device: GPUDevice) {
  const values = makeField(dims, 5, 'blobs');
  const stream = await compressVolume(device, values, dims, 8);
  return { stream, decoded: await decodeVolume(device, stream) };
}

describe('Isosurface', () => {
  gpuTest('newest wins: a pending isovalue is replaced, never queued', async ({ gpu }) => {
    const { stream, decoded } = await setup(gpu.device);
    // room for every surface: no growth retries in this test
    const iso = await Isosurface.create(gpu, stream, { initialCacheSlots: 1 << 20, initialVertexCapacity: 1 << 20 });
    const [lo, hi] = iso.info.valueRange;
    const values = [0.3, 0.4, 0.5, 0.6].map((f) => Math.fround(lo + f * (hi - lo)));
    const seen: number[] = [];
    iso.onStats((s) => seen.push(s.isovalue));
    // two in flight at once (the default), the next two replace each other, the last one wins
    for (const v of values) iso.setIsovalue(v);
    expect(iso.busy).toBe(true);
    const first = iso.compute(values[0]); // replaces values[3] as the pending one
    const last = iso.compute(values[2]);
    await expect(first).rejects.toBeInstanceOf(IsosurfaceSupersededError);
    const stats = await last;
    expect(seen).toEqual([values[0], values[1], values[2]]);
    expect(stats.triangles).toBe(marchingCubes(decoded, dims, values[2]).triangleCount);
    expect(iso.busy).toBe(false);
    iso.destroy();
    stream.destroy();
  });

  gpuTest('a budget below the default starting sizes shrinks them to fit; below the smallest it is refused', async ({ gpu }) => {
    const { stream } = await setup(gpu.device);
    const { cacheBytesFor, vertexBytesFor } = await import('../../../src/isosurface/budget.ts');
    const blocks = stream.info.blockCount;
    const perShard = Math.floor(gpu.limits.maxStorageBufferBindingSize / 4);
    const smallest = cacheBytesFor(1, blocks) + vertexBytesFor(1, 1, perShard);
    // Just above the smallest buffers: far below the default 10% of blocks + 64k vertices.
    const budget = smallest + 3000;
    const iso = await Isosurface.create(gpu, stream, { memoryBudgetBytes: budget });
    const result: IsosurfaceStats | Error = await iso
      .compute(Math.fround(iso.info.valueRange[0] + 0.9 * (iso.info.valueRange[1] - iso.info.valueRange[0])))
      .catch((e: Error) => e);
    // Whether or not the surface fits, the starting buffers did.
    if (result instanceof Error) expect(result).toBeInstanceOf(IsosurfaceBudgetError);
    else expect(result.cacheBytes + result.vertexBytes).toBeLessThanOrEqual(budget);
    iso.destroy();
    const refused = await Isosurface.create(gpu, stream, { memoryBudgetBytes: smallest - 1 }).catch((e: unknown) => e);
    expect(refused).toBeInstanceOf(IsosurfaceBudgetError);
    expect((refused as IsosurfaceBudgetError).neededBytes).toBe(smallest);
    expect((refused as Error).message).toContain(`need ${formatMB(smallest)}`);
    stream.destroy();
  });

  gpuTest('a surface over the memory budget is refused with a clear error and the previous one stays drawn', async ({ gpu }) => {
    const { stream, decoded } = await setup(gpu.device);
    const budget = 100_000;
    const iso = await Isosurface.create(gpu, stream, { initialCacheSlots: 8, initialVertexCapacity: 3000, memoryBudgetBytes: budget });
    const [lo, hi] = iso.info.valueRange;
    const small = Math.fround(lo + 0.9 * (hi - lo));
    const large = Math.fround(lo + 0.05 * (hi - lo));
    const errors: Error[] = [];
    iso.onError((e) => errors.push(e));
    const kept = await iso.compute(small);
    const keptVertices = await readVertices(iso);
    const version = iso.drawData.version;
    const error = await iso.compute(large).then(
      () => undefined,
      (e: unknown) => e,
    );
    expect(error).toBeInstanceOf(IsosurfaceBudgetError);
    const budgetError = error as IsosurfaceBudgetError;
    expect(budgetError.message).toContain(`the surface at iso ${large} needs `);
    expect(budgetError.message).toContain(`the budget is ${formatMB(budget)}; raise it`);
    expect(budgetError.neededBytes).toBeGreaterThan(budget);
    expect(budgetError.budgetBytes).toBe(budget);
    expect(errors).toEqual([error]);
    // the vertices and draw arguments still hold the previous surface (the
    // cache may have grown on the way: that alone fitted the budget)
    expect([...(await readVertices(iso))]).toEqual([...keptVertices]);
    expect(keptVertices.length / 2).toBe(kept.indices);
    // with room, the same surface grows what it needs and is exact
    iso.setMemoryBudget(64 << 20);
    const grown = await iso.compute(large);
    expect(grown.grew).toBe(true);
    expect(grown.triangles).toBe(marchingCubes(decoded, dims, large).triangleCount);
    expect(iso.drawData.version).toBeGreaterThan(version);
    expect(grown.cacheBytes + grown.vertexBytes).toBeLessThanOrEqual(64 << 20);
    iso.destroy();
    stream.destroy();
  });

  gpuTest('vertex overflow alone: the buffers grow, the decoded blocks count once, the cache is not redone', async ({ gpu }) => {
    const { stream, decoded } = await setup(gpu.device);
    const iso = await Isosurface.create(gpu, stream, { initialCacheSlots: 100_000, initialVertexCapacity: 10 });
    const [lo, hi] = iso.info.valueRange;
    const t = Math.fround(lo + 0.2 * (hi - lo));
    const stats: IsosurfaceStats = await iso.compute(t);
    expect(stats.grew).toBe(true);
    expect(stats.newBlocks).toBe(stats.activeBlocks); // cold cache: every active block decoded once
    expect(stats.triangles).toBe(marchingCubes(decoded, dims, t).triangleCount);
    expect(stats.stages.map((s) => s.label)).toContain('attempts before growth');
    const again = await iso.compute(t);
    expect(again.grew).toBe(false);
    expect(again.newBlocks).toBe(0);
    expect(again.hitRate).toBe(1);
    iso.destroy();
    stream.destroy();
  });

  gpuTest(
    'welded-vertex overflow alone: the vertex buffer grows, the indices are not regrown, the surface is the same',
    async ({ gpu }) => {
      // Lone voxels on the volume's z = 0 face: each an open piece of 4 triangles (12 indices) on 5 cut
      // edges, so more welded vertices than the quarter of the indices the vertex buffer starts with.
      const noiseDims: Dims = [14, 13, 3];
      const values = new Float32Array(noiseDims[0] * noiseDims[1] * noiseDims[2]);
      for (let y = 1; y < noiseDims[1]; y += 3) for (let x = 1; x < noiseDims[0]; x += 3) values[x + noiseDims[0] * y] = 1;
      const stream = await compressVolume(gpu.device, values, noiseDims, 16);
      const decoded = await decodeVolume(gpu.device, stream);
      const roomy = await Isosurface.create(gpu, stream, { initialCacheSlots: 100_000, initialVertexCapacity: 1 << 20 });
      const t = 0.5;
      const reference = await roomy.compute(t);
      const referenceSoup = await readVertices(roomy);
      roomy.destroy();
      expect(reference.vertices).toBeGreaterThan(reference.indices / 4);
      expect(reference.vertices).toBe(crossedEdges(decoded, noiseDims, t));

      const iso = await Isosurface.create(gpu, stream, { initialCacheSlots: 100_000, initialVertexCapacity: reference.indices });
      const indexBuffers = iso.drawData.shards.map((s) => s.indices);
      const vertexBuffer = iso.drawData.vertices;
      const stats = await iso.compute(t);
      expect(stats.grew).toBe(true);
      expect(stats.vertices).toBe(reference.vertices);
      expect(stats.triangles).toBe(marchingCubes(decoded, noiseDims, t).triangleCount);
      // the same index buffers (objects), a new vertex buffer
      expect(iso.drawData.shards.length).toBe(indexBuffers.length);
      iso.drawData.shards.forEach((s, k) => expect(s.indices).toBe(indexBuffers[k]));
      expect(iso.drawData.vertices).not.toBe(vertexBuffer);
      expect(await readVertices(iso)).toEqual(referenceSoup);
      iso.destroy();
      stream.destroy();
    },
  );

  gpuTest('the welded mesh of a closed surface is one connected manifold: V - E + F = 2, every edge in two triangles', async ({ gpu }) => {
    // A ball inside the volume: a sphere's surface, closed.
    const n = 22;
    const ball = new Float32Array(n * n * n);
    const c = (n - 1) / 2;
    for (let z = 0; z < n; z++)
      for (let y = 0; y < n; y++) for (let x = 0; x < n; x++) ball[x + n * (y + n * z)] = 8 - Math.hypot(x - c, y - c, z - c);
    const stream = await compressVolume(gpu.device, ball, [n, n, n], 16);
    const iso = await Isosurface.create(gpu, stream);
    const stats = await iso.compute(0.37);
    const mesh = await iso.readMesh();
    expect(mesh.indices.length).toBe(stats.indices);
    expect(mesh.vertices.length / 3).toBe(stats.vertices);
    const edges = new Map<string, number>();
    const used = new Uint8Array(stats.vertices);
    for (let t = 0; t < mesh.indices.length; t += 3) {
      for (let k = 0; k < 3; k++) {
        const a = mesh.indices[t + k];
        const b = mesh.indices[t + ((k + 1) % 3)];
        used[a] = 1;
        const key = a < b ? `${a},${b}` : `${b},${a}`;
        edges.set(key, (edges.get(key) ?? 0) + 1);
      }
    }
    // Every vertex used; welded (a soup's copies left apart would break both counts).
    expect(used.every((u) => u === 1)).toBe(true);
    expect([...edges.values()].every((k) => k === 2)).toBe(true);
    expect(stats.vertices - edges.size + stats.triangles).toBe(2);
    iso.destroy();
    stream.destroy();
  });

  gpuTest('destroy rejects what is waiting; a destroyed object refuses work', async ({ gpu }) => {
    const { stream } = await setup(gpu.device);
    const iso = await Isosurface.create(gpu, stream);
    const running = iso.compute(iso.info.valueRange[0] + 1);
    const waiting = iso.compute(iso.info.valueRange[0] + 2);
    iso.destroy();
    await expect(running).rejects.toThrow(/destroyed/);
    await expect(waiting).rejects.toThrow(/destroyed/);
    await expect(iso.compute(3)).rejects.toThrow(/destroyed/);
    await expect(iso.compute(NaN)).rejects.toThrow();
    stream.destroy();
  });
});
