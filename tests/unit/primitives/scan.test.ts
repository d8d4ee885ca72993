// ExclusiveScan against a CPU scan: every size the issue lists, full-range
// random u32 (so sums wrap) and 0/1 masks, counts from GPU buffers smaller
// than the buffers, poisoned outputs checked element by element (the tail
// past the count must stay poisoned), totals written to a GPU buffer. Every
// test runs on both kernel families (emulator and GPU path), the GPU path
// without and with subgroups.
import { describe, expect, test } from 'vitest';
import { ExclusiveScan } from '../../../src/primitives/scan.ts';
import { chooseSubgroups } from '../../../src/primitives/dispatch-records.ts';
import type { CountLike } from '../../../src/primitives/count.ts';
import { codePathRerun, gpuTest } from '../../helpers/gpu.ts';
import { readU32 } from '../../../src/gpu/buffers.ts';
import { summarizeAdapter } from '../../../src/gpu/device.ts';
import {
  SCAN_VARIANTS,
  POISON,
  SMALL_SIZES,
  largeSizes,
  cpuExclusiveScan,
  diff,
  gpuCount,
  poison,
  randomMask,
  randomU32,
  read,
  upload,
  variantOptions,
} from './helpers.ts';

const EXTRA = 37; // buffer elements past the count

/** Scans `data[0..n)` with the GPU count (or host number) and returns problems found. */
async function check(device: GPUDevice, scan: ExclusiveScan, data: Uint32Array, n: number, useHostCount = false): Promise<string[]> {
  const input = upload(device, 'test.input', data);
  const output = upload(device, 'test.output', new Uint32Array(0), data.length);
  const totals = upload(device, 'test.totals', new Uint32Array(0), 3);
  const countBuf = useHostCount ? undefined : gpuCount(device, n);
  const count: CountLike = countBuf ?? n;
  const encoder = device.createCommandEncoder();
  scan.encode(encoder, { input, output, count, totalOut: { buffer: totals, offset: 4 } });
  device.queue.submit([encoder.finish()]);
  const ref = cpuExclusiveScan(data, n);
  const problems: string[] = [];
  const d = diff(await read(device, output), ref.scan);
  if (d) problems.push(`n=${n}: ${d}`);
  const t = await read(device, totals);
  if (t[1] !== ref.total || t[0] !== POISON || t[2] !== POISON)
    problems.push(`n=${n}: totals buffer [${[...t]}], expected total ${ref.total} at word 1`);
  for (const b of [input, output, totals, countBuf?.buffer]) b?.destroy();
  return problems;
}

for (const variant of SCAN_VARIANTS)
  describe(`ExclusiveScan, ${variant.name} path`, () => {
    const path = variant.path;
    gpuTest('every size, random u32, GPU count below the buffer length, total to a GPU buffer', async ({ gpu }) => {
      const { device } = gpu;
      const opts = variantOptions(device, variant);
      if (!opts) return;
      const scan = await ExclusiveScan.create(device, { capacity: 2 ** 24 + EXTRA, ...opts });
      expect(scan.path).toBe(path);
      expect(scan.subgroups).toBe(variant.subgroups);
      const problems: string[] = [];
      // a rerun for another implementation (wgpu): the smallest large size (the unit suite has them all)
      for (const n of [...SMALL_SIZES, ...(codePathRerun ? [Math.min(...largeSizes(path))] : largeSizes(path))]) {
        problems.push(...(await check(device, scan, randomU32(n + EXTRA, n + 1), n)));
      }
      expect(problems).toEqual([]);
      scan.destroy();
    });

    gpuTest('0/1 masks of every density, host-number counts', async ({ gpu }) => {
      const { device } = gpu;
      const opts = variantOptions(device, variant);
      if (!opts) return;
      const scan = await ExclusiveScan.create(device, { capacity: 2 ** 20 + 3, ...opts });
      const problems: string[] = [];
      for (const n of [0, 1, 255, 4095, 65536, 2 ** 20 + 3]) {
        for (const density of [0, 0.01, 0.5, 1]) {
          problems.push(...(await check(device, scan, randomMask(n + EXTRA, density, n + 3), n, true)));
        }
      }
      expect(problems).toEqual([]);
      scan.destroy();
    });

    gpuTest('many levels (tiny chunks), 2D grids, one object reused across sizes', async ({ gpu }) => {
      const { device } = gpu;
      const opts = variantOptions(device, variant);
      if (!opts) return;
      const problems: string[] = [];
      // chunk 2 over 65537 elements gives 18 levels; a grid limit of 3
      // workgroups per dimension forces 2D grids at every level.
      // Workgroups of 16, 6 (a partial last subgroup where subgroups hold 4 or
      // more) and 1 invocation.
      for (const [chunk, maxPerDim, workgroupSize] of [
        [2, 3, 16],
        [3, 65535, 6],
        [7, 2, 1],
      ]) {
        const scan = await ExclusiveScan.create(device, {
          capacity: 65537,
          chunk,
          maxWorkgroupsPerDimension: maxPerDim,
          workgroupSize,
          ...opts,
        });
        for (const n of [0, 1, 2, 3, 4, 63, 64, 65, 257, 4095, 65537]) {
          problems.push(...(await check(device, scan, randomU32(n + EXTRA, n * chunk + 5), n)).map((p) => `chunk ${chunk}: ${p}`));
        }
        scan.destroy();
      }
      expect(problems).toEqual([]);
    });

    gpuTest('grow raises the capacity; counts above it are clamped', async ({ gpu }) => {
      const { device } = gpu;
      const opts = variantOptions(device, variant);
      if (!opts) return;
      const scan = await ExclusiveScan.create(device, { capacity: 100, ...opts });
      expect(scan.capacity).toBe(100);
      const data = randomU32(70000 + EXTRA, 11);
      // Above the capacity: only the first 100 elements are scanned.
      const input = upload(device, 'test.input', data);
      const output = upload(device, 'test.output', new Uint32Array(0), data.length);
      const totals = upload(device, 'test.totals', new Uint32Array(0), 1);
      let encoder = device.createCommandEncoder();
      scan.encode(encoder, { input, output, count: 70000, totalOut: { buffer: totals, offset: 0 } });
      device.queue.submit([encoder.finish()]);
      const clamped = cpuExclusiveScan(data, 100);
      expect(diff(await read(device, output), clamped.scan)).toBe('');
      expect((await read(device, totals))[0]).toBe(clamped.total);

      scan.grow(70000);
      expect(scan.capacity).toBe(70000);
      poison(device, output);
      encoder = device.createCommandEncoder();
      scan.encode(encoder, { input, output, count: 70000, totalOut: { buffer: totals, offset: 0 } });
      device.queue.submit([encoder.finish()]);
      const full = cpuExclusiveScan(data, 70000);
      expect(diff(await read(device, output), full.scan)).toBe('');
      expect((await read(device, totals))[0]).toBe(full.total);
      for (const b of [input, output, totals]) b.destroy();
      scan.destroy();
    });

    gpuTest('two scans in one encoder share the object; the second count comes from the first total', async ({ gpu }) => {
      const { device } = gpu;
      const opts = variantOptions(device, variant);
      if (!opts) return;
      const scan = await ExclusiveScan.create(device, { capacity: 5000, ...opts });
      const a = randomMask(5000, 0.3, 21);
      const b = randomU32(5000, 22);
      const inA = upload(device, 'a', a);
      const outA = upload(device, 'outA', new Uint32Array(0), 5000);
      const inB = upload(device, 'b', b);
      const outB = upload(device, 'outB', new Uint32Array(0), 5000);
      const totals = upload(device, 'totals', new Uint32Array(0), 2);
      const encoder = device.createCommandEncoder();
      scan.encode(encoder, { input: inA, output: outA, count: gpuCount(device, 5000), totalOut: { buffer: totals, offset: 0 } });
      // The number of ones in `a`, known only to the GPU, is the second count.
      scan.encode(encoder, { input: inB, output: outB, count: { buffer: totals, offset: 0 }, totalOut: { buffer: totals, offset: 4 } });
      device.queue.submit([encoder.finish()]);
      const refA = cpuExclusiveScan(a);
      const refB = cpuExclusiveScan(b, refA.total);
      expect(diff(await read(device, outA), refA.scan)).toBe('');
      expect(diff(await read(device, outB), refB.scan)).toBe('');
      expect([...(await read(device, totals))]).toEqual([refA.total, refB.total]);
      scan.destroy();
    });

    gpuTest(
      "2^27 elements (or the binding limit), the issue's upper bound (pattern computed on the fly, checked in slices)",
      async ({ gpu }) => {
        const { device } = gpu;
        const opts = variantOptions(device, variant);
        if (!opts) return;
        // The GPU path at 2^27 takes minutes on SwiftShader; its multi-level
        // structure is exercised by the tiny-tile and grid-limit cases above.
        // (Also where the implementation does not say what it is, e.g. wgpu in Deno.)
        const info = (device as GPUDevice & { adapterInfo?: GPUAdapterInfo }).adapterInfo;
        if (path === 'gpu' && (!info || summarizeAdapter(info).software)) return;
        // 2^27, or the most one storage binding holds (2^25 - 5 at WebGPU's default limits).
        const maxWords = Math.floor(Math.min(device.limits.maxStorageBufferBindingSize, device.limits.maxBufferSize) / 4);
        const n = Math.min(2 ** 27, maxWords - 5);
        const length = n + 5;
        // 0..7 per element from a multiplicative hash: no 512 MiB host arrays.
        const value = (i: number) => Math.imul(i, 0x9e3779b1) >>> 29;
        const input = device.createBuffer({ label: 'test.input', size: length * 4, usage: GPUBufferUsage.STORAGE, mappedAtCreation: true });
        const words = new Uint32Array(input.getMappedRange());
        for (let i = 0; i < length; i++) words[i] = value(i);
        input.unmap();
        const output = device.createBuffer({
          label: 'test.output',
          size: length * 4,
          usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC,
          mappedAtCreation: true,
        });
        new Uint32Array(output.getMappedRange()).fill(POISON);
        output.unmap();
        const totals = upload(device, 'test.totals', new Uint32Array(0), 1);
        const scan = await ExclusiveScan.create(device, { capacity: length, ...opts });
        const encoder = device.createCommandEncoder();
        scan.encode(encoder, { input, output, count: gpuCount(device, n), totalOut: { buffer: totals, offset: 0 } });
        device.queue.submit([encoder.finish()]);
        let sum = 0;
        let wrong = 0;
        let first = '';
        const slice = 2 ** 23;
        for (let start = 0; start < length; start += slice) {
          const got = await readU32(device, output, start * 4, Math.min(slice, length - start));
          for (let k = 0; k < got.length; k++) {
            const i = start + k;
            const want = i < n ? sum : POISON;
            if (got[k] !== want) {
              wrong++;
              first ||= `[${i}] ${got[k]} != ${want}`;
            }
            if (i < n) sum = (sum + value(i)) >>> 0;
          }
        }
        expect(first).toBe('');
        expect(wrong).toBe(0);
        expect((await read(device, totals))[0]).toBe(sum);
        for (const b of [input, output, totals]) b.destroy();
        scan.destroy();
      },
    );
  });

test('chooseSubgroups: GPU path only, on by default where the feature is, forced off or demanded by the option', () => {
  const withFeature = { features: new Set(['subgroups']) } as unknown as GPUDevice;
  const without = { features: new Set<string>() } as unknown as GPUDevice;
  expect(chooseSubgroups(withFeature, {}, 'gpu')).toBe(true);
  expect(chooseSubgroups(withFeature, { subgroups: false }, 'gpu')).toBe(false);
  expect(chooseSubgroups(withFeature, { subgroups: true }, 'emulator')).toBe(false);
  expect(chooseSubgroups(without, {}, 'gpu')).toBe(false);
  expect(() => chooseSubgroups(without, { subgroups: true }, 'gpu')).toThrow(/subgroups/);
});
