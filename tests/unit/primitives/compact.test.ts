// StreamCompact and StreamCompactIds against a CPU compaction, with masks of
// densities 0, 1%, 50% and 100% at every listed size, counts from GPU buffers
// smaller than the buffers, and poisoned outputs checked past the kept count;
// both kernel families (emulator and GPU path).
import { describe, expect } from 'vitest';
import { StreamCompact, StreamCompactIds } from '../../../src/primitives/compact.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import {
  LARGE_SIZES,
  PATHS,
  SMALL_SIZES,
  cpuExclusiveScan,
  diff,
  gpuCount,
  poison,
  randomMask,
  randomU32,
  read,
  upload,
} from './helpers.ts';

const DENSITIES = [0, 0.01, 0.5, 1];
const EXTRA = 29;

function cpuCompact(mask: Uint32Array, values: Uint32Array | undefined, n: number): Uint32Array {
  const out = new Uint32Array(n);
  let k = 0;
  for (let i = 0; i < n; i++) if (mask[i] !== 0) out[k++] = values ? values[i] : i;
  return out.subarray(0, k);
}

for (const path of PATHS)
  describe(`StreamCompact / StreamCompactIds, ${path} path`, () => {
    gpuTest('every size and density, GPU count below the buffer length', async ({ gpu }) => {
      const { device } = gpu;
      const compact = await StreamCompact.create(device, { path });
      const compactIds = await StreamCompactIds.create(device, { path });
      expect([compact.path, compactIds.path]).toEqual([path, path]);
      const problems: string[] = [];
      const cases: [number, number][] = [];
      for (const n of SMALL_SIZES) for (const d of DENSITIES) cases.push([n, d]);
      // Large sizes: the four densities spread over the three sizes.
      const [odd, mid, big] = LARGE_SIZES;
      cases.push([odd, 0.01], [mid, 0], [mid, 1], [big, 0.5], [65535 * 64 + 1, 0.5]);
      for (const [n, density] of cases) {
        const length = n + EXTRA;
        // Elements past the count are set, so reading past it would show.
        const mask = randomMask(length, density, n + Math.round(density * 100));
        mask.fill(1, n);
        const offsets = cpuExclusiveScan(mask).scan;
        const values = randomU32(length, n + 17);
        const maskBuf = upload(device, 'test.mask', mask);
        const offsetsBuf = upload(device, 'test.offsets', offsets);
        const valuesBuf = upload(device, 'test.values', values);
        const out = upload(device, 'test.out', new Uint32Array(0), length);
        const outIds = upload(device, 'test.outIds', new Uint32Array(0), length);
        const count = gpuCount(device, n);
        const encoder = device.createCommandEncoder();
        compact.encode(encoder, { mask: maskBuf, offsets: offsetsBuf, values: valuesBuf, output: out, count });
        compactIds.encode(encoder, { mask: maskBuf, offsets: offsetsBuf, output: outIds, count });
        device.queue.submit([encoder.finish()]);
        const dv = diff(await read(device, out), cpuCompact(mask, values, n));
        const di = diff(await read(device, outIds), cpuCompact(mask, undefined, n));
        if (dv) problems.push(`values n=${n} density=${density}: ${dv}`);
        if (di) problems.push(`ids n=${n} density=${density}: ${di}`);
        for (const b of [maskBuf, offsetsBuf, valuesBuf, out, outIds, count.buffer]) b.destroy();
      }
      expect(problems).toEqual([]);
      compact.destroy();
      compactIds.destroy();
    });

    gpuTest('2D grids, host counts, bind groups reused across calls', async ({ gpu }) => {
      const { device } = gpu;
      const compactIds = await StreamCompactIds.create(device, { maxWorkgroupsPerDimension: 2, workgroupSize: 8, chunk: 3, path });
      const length = 5000;
      const mask = randomMask(length, 0.5, 5);
      const offsets = cpuExclusiveScan(mask).scan;
      const maskBuf = upload(device, 'test.mask', mask);
      const offsetsBuf = upload(device, 'test.offsets', offsets);
      const out = upload(device, 'test.out', new Uint32Array(0), length);
      const problems: string[] = [];
      for (const n of [0, 1, 23, 24, 25, 48, 49, 1000, 5000]) {
        poison(device, out);
        const encoder = device.createCommandEncoder();
        compactIds.encode(encoder, { mask: maskBuf, offsets: offsetsBuf, output: out, count: n });
        device.queue.submit([encoder.finish()]);
        const d = diff(await read(device, out), cpuCompact(mask, undefined, n));
        if (d) problems.push(`n=${n}: ${d}`);
      }
      expect(problems).toEqual([]);
      compactIds.destroy();
    });
  });
