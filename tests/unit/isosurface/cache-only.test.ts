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
});
