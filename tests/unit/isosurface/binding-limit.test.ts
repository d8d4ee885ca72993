// Every storage binding stays within maxStorageBufferBindingSize: the cache's
// slot data (256 B per slot, bound whole by the decoder, classification and
// vertex passes) never grows past one binding, and a surface that would need
// more slots is refused with a clear error that keeps the previous surface;
// a volume whose per-block buffers exceed one binding is refused at creation.
// The limit is lowered through IsosurfaceOptions.maxStorageBindingBytes (a
// device cannot be asked for less than WebGPU's default 128 MiB).
import { describe, expect } from 'vitest';
import { Isosurface } from '../../../src/isosurface/isosurface.ts';
import { activeBlocks } from '../../../src/isosurface/lru-model.ts';
import { marchingCubes } from '../../../src/mc/serial-mc.ts';
import type { Dims } from '../../../src/core/naming.ts';
import { blockRanges } from '../../../src/zfp/cpu/codec.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { compressVolume, decodeVolume, makeField } from './helpers.ts';
import { readVertices } from '../../helpers/isosurface-readback.ts';

const dims: Dims = [37, 30, 25];

describe('storage binding limit', () => {
  gpuTest('the cache stops at one binding of slot data; a surface needing more is refused, the previous one stays', async ({ gpu }) => {
    const { device } = gpu;
    const stream = await compressVolume(device, makeField(dims, 31, 'blobs'), dims, 8);
    const decoded = await decodeVolume(device, stream);
    const ranges = blockRanges(decoded, dims);
    const probe = await Isosurface.create(gpu, stream);
    const { blockGrid, valueRange } = probe.info;
    probe.destroy();
    const [lo, hi] = valueRange;
    const small = Math.fround(lo + 0.7 * (hi - lo));
    const large = Math.fround(lo + 0.1 * (hi - lo));
    const nSmall = activeBlocks(ranges, blockGrid, small).length;
    const nLarge = activeBlocks(ranges, blockGrid, large).length;
    expect(nSmall).toBeGreaterThan(4);
    expect(nLarge).toBeGreaterThan(nSmall + 2);
    const maxSlots = nSmall + 1; // room for the small surface, not the large one
    const iso = await Isosurface.create(gpu, stream, { initialCacheSlots: 4, maxStorageBindingBytes: maxSlots * 256 });
    const errors: Error[] = [];
    iso.onError((e) => errors.push(e));
    const kept = await iso.compute(small);
    expect(kept.grew).toBe(true);
    expect(kept.cacheSlots).toBeLessThanOrEqual(maxSlots); // growth headroom capped at the binding
    expect(kept.triangles).toBe(marchingCubes(decoded, dims, small).triangleCount);
    const keptVertices = await readVertices(iso);
    const refused = await iso.compute(large).catch((e: unknown) => e);
    expect(refused).toBeInstanceOf(Error);
    expect((refused as Error).message).toBe(
      `Isosurface: the surface at iso ${large} needs ${nLarge} cache slots (${((nLarge * 256) / 2 ** 20).toFixed(2)} MB of decoded blocks), ` +
        `but this device binds at most ${maxSlots} slots (${((maxSlots * 256) / 2 ** 20).toFixed(2)} MB: maxStorageBufferBindingSize) in one buffer. The previous surface is kept.`,
    );
    expect(errors).toEqual([refused]);
    expect(await readVertices(iso)).toEqual(keptVertices);
    expect((await iso.compute(small)).triangles).toBe(kept.triangles);
    iso.destroy();

    // Per-block buffers (8 B per block) larger than one binding: refused at creation, naming the file.
    const blocks = stream.info.blockCount;
    const tooSmall = await Isosurface.create(gpu, stream, { maxStorageBindingBytes: blocks * 8 - 256 }).catch((e: unknown) => e);
    expect(tooSmall).toBeInstanceOf(RangeError);
    expect((tooSmall as Error).message).toMatch(
      new RegExp(`^${stream.info.fileName}: ${blocks} blocks need .* per-block buffers in one storage binding; this device binds at most`),
    );
    stream.destroy();
  });
});
