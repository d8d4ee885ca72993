// IsosurfaceOptions.cacheOnly (the ray caster's surface): each isovalue
// selects and decodes the same blocks as a full surface, and makes no
// triangles. Over random fields of awkward sizes, at several isovalues one
// after the other (the cache kept between them), the cache-only surface
// caches exactly the blocks the full one caches, with the same 64 decoded
// values each, reports no triangles and no vertex bytes beyond its smallest
// buffers, and holds fewer bytes (no classification buffers per slot).
import { describe, expect } from 'vitest';
import { readF32, readU32 } from '../../../src/gpu/buffers.ts';
import { Isosurface } from '../../../src/isosurface/isosurface.ts';
import type { IsosurfaceDrawData } from '../../../src/isosurface/types.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { meteredGpu } from '../../../src/gpu/memory-meter.ts';
import { cacheBytesFor } from '../../../src/isosurface/budget.ts';
import { compressVolume, makeField, testKernelOptions } from './helpers.ts';

const NONE = 0xffffffff;

/** Per cached block id, its 64 decoded values. */
async function cached(device: GPUDevice, data: IsosurfaceDrawData): Promise<Map<number, number[]>> {
  const map = await readU32(device, data.blockToSlot, 0, data.info.blockCount);
  const out = new Map<number, number[]>();
  const used = [...map].filter((s) => s !== NONE);
  if (used.length === 0) return out;
  const slots = await readF32(device, data.slotData, 0, (Math.max(...used) + 1) * 64);
  map.forEach((slot, block) => {
    if (slot !== NONE) out.set(block, [...slots.subarray(slot * 64, slot * 64 + 64)]);
  });
  return out;
}

describe('Isosurface cacheOnly', () => {
  gpuTest('caches the blocks a full surface caches, with the same values; no triangles; fewer bytes', async ({ gpu }) => {
    for (const dims of [
      [1, 1, 1],
      [5, 9, 3],
      [26, 30, 21],
      [65, 17, 33],
    ] as [number, number, number][]) {
      const field = makeField(dims, 7, 'blobs');
      const full = await Isosurface.create(gpu, await compressVolume(gpu.device, field, dims, 16), { ...testKernelOptions });
      const only = await Isosurface.create(gpu, await compressVolume(gpu.device, field, dims, 16), {
        ...testKernelOptions,
        cacheOnly: true,
      });
      try {
        const [lo, hi] = full.info.valueRange;
        for (const f of [0.3, 0.45, 0.7]) {
          const iso = lo + f * (hi - lo);
          const a = await full.compute(iso);
          const b = await only.compute(iso);
          expect(b.activeBlocks, `${dims} at ${f}`).toBe(a.activeBlocks);
          expect(b.triangles).toBe(0);
          expect(b.indices).toBe(0);
          // what the cost model learns: at least the active blocks' decoded values, at most what the cache holds
          expect(b.cacheBytesNeeded).toBeGreaterThanOrEqual(b.activeBlocks * 64 * 4);
          expect(b.cacheBytesNeeded).toBeLessThanOrEqual(b.cacheBytes);
          const ca = await cached(gpu.device, full.drawData);
          const cb = await cached(gpu.device, only.drawData);
          expect([...cb.keys()].sort((x, y) => x - y)).toEqual([...ca.keys()].sort((x, y) => x - y));
          for (const [block, values] of ca) expect(cb.get(block)).toEqual(values);
          if (a.activeBlocks > 0) expect(a.triangles).toBeGreaterThan(0);
        }
        expect(only.budgetedBytes).toBeLessThan(full.budgetedBytes);
      } finally {
        full.destroy();
        only.destroy();
      }
    }
  });

  gpuTest('a cache that grows holds its old and new slots at once only where the budget has room for both', async ({ gpu }) => {
    const dims: [number, number, number] = [65, 57, 49];
    const field = makeField(dims, 11, 'blobs');
    const stream = await compressVolume(gpu.device, field, dims, 16);
    const options = { ...testKernelOptions, cacheOnly: true, initialCacheSlots: 8 };
    // the blocks each isovalue makes active (a surface without a budget to speak of)
    const probe = await Isosurface.create(gpu, stream, options);
    const [lo, hi] = probe.info.valueRange;
    const few = lo + 0.75 * (hi - lo);
    const many = lo + 0.35 * (hi - lo);
    const fewActive = (await probe.compute(few)).activeBlocks;
    const manyActive = (await probe.compute(many)).activeBlocks;
    probe.destroy();
    expect(fewActive).toBeGreaterThan(100);
    expect(manyActive).toBeGreaterThan(2 * fewActive);
    // a budget the larger surface fits in, but not beside the smaller one's cache
    const { gpu: metered, meter } = meteredGpu(gpu);
    const made = await Isosurface.create(metered, stream, options);
    const vertexBytes = made.budgetedBytes - cacheBytesFor(8, made.info.blockCount, true);
    made.destroy();
    const budget = vertexBytes + cacheBytesFor(manyActive, made.info.blockCount, true) + 1024;
    meter.resetPeak();
    const before = meter.bytes;
    const surface = await Isosurface.create(metered, stream, { ...options, memoryBudgetBytes: budget });
    // what the surface holds besides its cache and vertices (per-block state), made once
    const fixed = meter.bytes - before - surface.budgetedBytes;
    try {
      expect((await surface.compute(few)).activeBlocks).toBe(fewActive);
      const grown = await surface.compute(many);
      expect(grown.activeBlocks).toBe(manyActive);
      expect(surface.budgetedBytes).toBeLessThanOrEqual(budget);
      // the peak: never the old cache beside the new (the statistics' staging buffers aside)
      expect(meter.peak - before - fixed).toBeLessThanOrEqual(budget + 16 * 1024);
      // and what it cached is what a surface without a budget caches
      const free = await Isosurface.create(gpu, stream, options);
      await free.compute(many);
      const a = await cached(gpu.device, free.drawData);
      const b = await cached(gpu.device, surface.drawData);
      expect([...b.keys()].sort((x, y) => x - y)).toEqual([...a.keys()].sort((x, y) => x - y));
      free.destroy();
    } finally {
      surface.destroy();
      stream.destroy();
    }
  });
});
