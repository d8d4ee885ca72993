// SlotRangeReducer (src/isosurface/slot-ranges.ts, slot_ranges.wgsl): [min,
// max] per listed slot over its blocks' ranges, on the GPU, against the CPU
// on random ranges: blocks per chunk of every chunk edge (1, 8, 27, 64, 512,
// 4096), awkward slot counts (0, 1, 63, 64, 65, and past the 4096 workgroups
// a dispatch strides over), slots listed in any order and more than once,
// blocks with the empty range among them.
import { describe, expect } from 'vitest';
import { SlotRangeReducer } from '../../../src/isosurface/slot-ranges.ts';
import { mulberry32 } from '../../../src/util/random.ts';
import { gpuTest } from '../../helpers/gpu.ts';

const FLT_MAX = 3.4028234663852886e38;

describe('SlotRangeReducer', () => {
  gpuTest('min and max per listed slot = the CPU over the same block ranges', async ({ gpu }) => {
    const { device } = gpu;
    const random = mulberry32(3);
    for (const [per, poolSlots, counts] of [
      [1, 5000, [0, 1, 63, 64, 65, 4097, 4800]],
      [8, 300, [1, 65, 600]],
      [27, 70, [63, 64]],
      [64, 90, [1, 65, 200]],
      [512, 9, [9, 20]],
      [4096, 3, [1, 3]],
    ] as [number, number, number[]][]) {
      const ranges = new Float32Array(2 * per * poolSlots);
      for (let b = 0; b < per * poolSlots; b++) {
        if (random() < 0.1) {
          // a block with no voxel in the volume
          ranges.set([FLT_MAX, -FLT_MAX], 2 * b);
          continue;
        }
        const a = Math.fround((random() - 0.5) * 1e4);
        const c = Math.fround((random() - 0.5) * 1e4);
        ranges.set([Math.min(a, c), Math.max(a, c)], 2 * b);
      }
      // a slot whose blocks all have the empty range
      for (let b = 0; b < per; b++) ranges.set([FLT_MAX, -FLT_MAX], 2 * b);
      const buffer = device.createBuffer({ size: ranges.byteLength, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST });
      device.queue.writeBuffer(buffer, 0, ranges);
      const reducer = await SlotRangeReducer.create(device, buffer, per);
      try {
        // the reads in flight together share one staging buffer, one after the other
        const lists = counts.map((n) => Array.from({ length: n }, () => Math.floor(random() * poolSlots)));
        const results = await Promise.all(lists.map((l) => reducer.read(l)));
        lists.forEach((slots, k) => {
          const expected = new Float32Array(2 * slots.length);
          slots.forEach((s, i) => {
            let lo = FLT_MAX;
            let hi = -FLT_MAX;
            for (let b = s * per; b < (s + 1) * per; b++) {
              lo = Math.min(lo, ranges[2 * b]);
              hi = Math.max(hi, ranges[2 * b + 1]);
            }
            expected.set([lo, hi], 2 * i);
          });
          expect(results[k], `${per} blocks per chunk, ${slots.length} slots`).toEqual(expected);
        });
      } finally {
        reducer.destroy();
        buffer.destroy();
      }
    }
  });
});
