// The per-device pipeline cache seen from the modules: a second Isosurface on
// the same device (same or another volume), a second decoder, encoder, scan,
// compaction, sort or IndirectArgs compiles no shader module and creates no
// compute pipeline; different override constants (a lowered workgroup grid
// limit) do create new ones. The surfaces stay those of the serial MC.
import { describe, expect } from 'vitest';
import type { Dims } from '../../../src/core/naming.ts';
import { Isosurface } from '../../../src/isosurface/isosurface.ts';
import { marchingCubes } from '../../../src/mc/serial-mc.ts';
import { IndirectArgs, RadixSortByKey, StreamCompact, StreamCompactIds, ExclusiveScan } from '../../../src/primitives/index.ts';
import { ZfpDecoder } from '../../../src/zfp/decoder.ts';
import { ZfpEncoder } from '../../../src/zfp/encoder.ts';
import { countCompilations } from '../../helpers/count-compilations.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { compressVolume, decodeVolume, makeField } from './helpers.ts';

describe('pipelines are compiled once per device', () => {
  gpuTest('a second Isosurface.create compiles nothing; other constants compile anew', async ({ gpu }) => {
    const { device } = gpu;
    const dimsA: Dims = [30, 27, 22];
    const dimsB: Dims = [17, 40, 9];
    const streamA = await compressVolume(device, makeField(dimsA, 5, 'blobs'), dimsA, 8);
    const streamB = await compressVolume(device, makeField(dimsB, 9, 'noise'), dimsB, 6);
    const decodedA = await decodeVolume(device, streamA);
    const decodedB = await decodeVolume(device, streamB);

    const first = await Isosurface.create(gpu, streamA);
    const [lo, hi] = first.info.valueRange;
    const isoA = Math.fround(lo + 0.4 * (hi - lo));
    const want = marchingCubes(decodedA, dimsA, isoA).triangleCount;
    expect(want).toBeGreaterThan(0);
    expect((await first.compute(isoA)).triangles).toBe(want);

    const count = countCompilations(device);
    let second!: Isosurface;
    let other!: Isosurface;
    try {
      second = await Isosurface.create(gpu, streamA);
      other = await Isosurface.create(gpu, streamB, { initialCacheSlots: 3 });
      expect({ modules: count.modules, pipelines: count.pipelines }).toEqual({ modules: 0, pipelines: 0 });
    } finally {
      count.restore();
    }
    expect((await second.compute(isoA)).triangles).toBe(want);
    const [loB, hiB] = other.info.valueRange;
    const isoB = Math.fround(loB + 0.5 * (hiB - loB));
    // The cache grows from 3 slots (more submissions, bind groups rebuilt): still nothing new compiled.
    const again = countCompilations(device);
    try {
      expect((await other.compute(isoB)).triangles).toBe(marchingCubes(decodedB, dimsB, isoB).triangleCount);
      expect({ modules: again.modules, pipelines: again.pipelines }).toEqual({ modules: 0, pipelines: 0 });
    } finally {
      again.restore();
    }

    // A lowered grid limit is another override constant: new pipelines, same surface.
    const lowered = countCompilations(device);
    let small!: Isosurface;
    try {
      small = await Isosurface.create(gpu, streamA, { maxWorkgroupsPerDimension: 3 });
      expect(lowered.pipelines).toBeGreaterThan(0);
    } finally {
      lowered.restore();
    }
    expect((await small.compute(isoA)).triangles).toBe(want);
    for (const iso of [first, second, other, small]) iso.destroy();
    streamA.destroy();
    streamB.destroy();
  });

  gpuTest('a second decoder, encoder, scan, compaction, sort and IndirectArgs compile nothing', async ({ gpu }) => {
    const { device } = gpu;
    const make = () =>
      Promise.all([
        ZfpDecoder.create(device),
        ZfpEncoder.create(device, ['float32', 'uint16']),
        ExclusiveScan.create(device, { capacity: 1000 }),
        StreamCompact.create(device),
        StreamCompactIds.create(device),
        RadixSortByKey.create(device, { capacity: 1000 }),
        IndirectArgs.create(device, { itemsPerWorkgroup: 64 }),
      ]);
    const firsts = await make();
    const count = countCompilations(device);
    const seconds: { destroy(): void }[] = [];
    try {
      seconds.push(...(await make()));
      // A scan of another capacity has the same kernels.
      seconds.push(await ExclusiveScan.create(device, { capacity: 5_000_000 }));
      expect({ modules: count.modules, pipelines: count.pipelines }).toEqual({ modules: 0, pipelines: 0 });
    } finally {
      count.restore();
    }
    for (const o of [...firsts, ...seconds]) o.destroy();
  });
});
