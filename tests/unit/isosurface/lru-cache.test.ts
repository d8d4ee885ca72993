// The GPU cache against a CPU model of Algorithm 1 (src/isosurface/lru-model.ts):
// a scripted sequence of isovalues on a small volume with a small cache must
// give, after every surface, the same active and new block counts and the
// same slot <-> block maps and LRU order, slot for slot: exactly the evictions
// an LRU makes, including growth (the model grows by the same policy), log
// compactions (the log's tail checked) and a reset to the initial capacity.
import { describe, expect } from 'vitest';
import { grownCapacity } from '../../../src/isosurface/budget.ts';
import { Isosurface } from '../../../src/isosurface/isosurface.ts';
import { activeBlocks, LruCacheModel } from '../../../src/isosurface/lru-model.ts';
import { C, logSizeFor } from '../../../src/isosurface/layout.ts';
import { readU32 } from '../../../src/gpu/buffers.ts';
import type { Dims } from '../../../src/core/naming.ts';
import { blockRanges } from '../../../src/zfp/cpu/codec.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { compressVolume, decodeVolume, makeField, testDecoderPath, testKernelOptions, testPrimitivePath } from './helpers.ts';
import { readCacheState } from '../../helpers/isosurface-readback.ts';

describe('LRU block cache', () => {
  gpuTest('evicts, grows and resets exactly as the CPU model of Algorithm 1', async ({ gpu }) => {
    const { device } = gpu;
    const dims: Dims = [26, 21, 17];
    const values = makeField(dims, 2024, 'blobs');
    const stream = await compressVolume(device, values, dims, 12);
    const decoded = await decodeVolume(device, stream);
    const ranges = blockRanges(decoded, dims);
    const initialSlots = 12;
    const iso = await Isosurface.create(gpu, stream, {
      initialCacheSlots: initialSlots,
      initialVertexCapacity: 1 << 16,
      ...testKernelOptions,
    });
    if (testDecoderPath !== 'auto') expect(iso.pipeline.parts.decoder.path, 'forced decoder path').toBe(testDecoderPath);
    if (testPrimitivePath !== 'auto') {
      const { scan, slotScan, compact, compactIds } = iso.pipeline.parts;
      expect([scan.path, slotScan.path, compact.path, compactIds.path], 'ZFPISO_KERNEL_PATH').toEqual(Array(4).fill(testPrimitivePath));
      // the GPU path's scans use subgroups wherever the device has them (Dawn on SwiftShader does)
      const subgroups = device.features.has('subgroups');
      if (testPrimitivePath === 'gpu') expect([scan.subgroups, slotScan.subgroups]).toEqual([subgroups, subgroups]);
    }
    expect([...(await iso.readBlockRanges())]).toEqual([...ranges]);
    const grid = iso.info.blockGrid;
    const model = new LruCacheModel(iso.info.blockCount, initialSlots);
    const [lo, hi] = iso.info.valueRange;
    const at = (f: number) => Math.fround(lo + (hi - lo) * f);
    // nested surfaces up and down, repeats, jumps, a reset, and surfaces
    // larger than the cache (growth); fractions of the value range
    const script: (number | 'reset')[] = [
      0.9,
      0.8,
      0.7,
      0.85,
      0.6,
      0.95,
      0.5,
      0.9,
      0.3,
      0.3,
      0.75,
      'reset',
      0.65,
      0.2,
      0.92,
      0.1,
      0.55,
      0.05,
      0.88,
    ];
    let evictions = 0;
    let growths = 0;
    let hits = 0;
    // The log's tail, as lru.wgsl keeps it: compacted to `slots` entries when
    // a computation's appends would not fit, `slots` after a reset or growth.
    let tail = initialSlots;
    let compactions = 0;
    const counters = iso.pipeline.parts.counters.buffer;
    for (const step of script) {
      if (step === 'reset') {
        await iso.resetCache();
        model.reset(initialSlots);
        tail = initialSlots;
        continue;
      }
      const t = at(step);
      const active = activeBlocks(ranges, grid, t);
      let update = model.update(active);
      if (!update) {
        model.grow(grownCapacity(model.capacity, active.length, iso.info.blockCount));
        update = model.update(active)!;
        growths++;
        tail = model.capacity;
      }
      if (tail + active.length > logSizeFor(model.capacity)) {
        tail = model.capacity;
        compactions++;
      }
      tail += active.length;
      evictions += update.evicted.length;
      hits += active.length - update.newBlocks.length;
      const stats = await iso.compute(t);
      const what = `iso ${t} (${step} of the range)`;
      expect(stats.activeBlocks, what).toBe(active.length);
      expect(stats.newBlocks, what).toBe(update.newBlocks.length);
      expect(stats.cacheSlots, what).toBe(model.capacity);
      expect(stats.cacheSlotsUsed, what).toBe(model.slotsUsed);
      const state = await readCacheState(iso);
      expect([...state.slotToBlock], what).toEqual([...model.slotToBlock]);
      expect([...state.blockToSlot], what).toEqual([...model.blockToSlot]);
      expect([...state.lruOrder], what).toEqual(model.order);
      expect((await readU32(device, counters, C.logTail * 4, 1))[0], what).toBe(tail);
    }
    // the script exercised what it is for
    expect(evictions).toBeGreaterThan(20);
    expect(growths).toBeGreaterThanOrEqual(2);
    expect(hits).toBeGreaterThan(20);
    expect(compactions).toBeGreaterThanOrEqual(2);
    iso.destroy();
    stream.destroy();
  });
});
