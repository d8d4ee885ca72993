// RadixSortByKey against a CPU stable sort: keys with all bits random, few
// distinct values (stability shows in the values), already sorted and
// reverse sorted; ascending and descending; every listed size; counts from
// GPU buffers smaller than the buffers; poisoned outputs checked in full.
// Every test runs on both kernel families (emulator and GPU path), the GPU
// path's digit-table scan without and with subgroups.
import { describe, expect } from 'vitest';
import { ExclusiveScan } from '../../../src/primitives/scan.ts';
import { StreamCompact, StreamCompactIds } from '../../../src/primitives/compact.ts';
import { RadixSortByKey } from '../../../src/primitives/sort.ts';
import { codePathRerun, gpuTest } from '../../helpers/gpu.ts';
import {
  LARGE_SIZES,
  SCAN_VARIANTS,
  largeSizes,
  SMALL_SIZES,
  cpuSortPermutation,
  diff,
  gpuCount,
  poison,
  randomMask,
  randomU32,
  read,
  rng,
  upload,
  variantOptions,
} from './helpers.ts';

type Pattern = 'random' | 'few' | 'sorted' | 'reverse';
const PATTERNS: Pattern[] = ['random', 'few', 'sorted', 'reverse'];
const EXTRA = 19;

function makeKeys(pattern: Pattern, length: number, n: number, seed: number): Uint32Array<ArrayBuffer> {
  const keys = randomU32(length, seed);
  const next = rng(seed ^ 0x5bd1e995);
  const step = Math.max(1, Math.floor(2 ** 32 / Math.max(1, n)));
  for (let i = 0; i < n; i++) {
    if (pattern === 'few') keys[i] = [7, 0xffffffff, 1 << 20, 7 << 28, 0][next() % 5];
    // Sorted runs with duplicates (every key twice), spanning all 32 bits.
    else if (pattern === 'sorted') keys[i] = ((i >> 1) * step * 2) >>> 0;
    else if (pattern === 'reverse') keys[i] = (0xffffffff - (i >> 1) * step * 2) >>> 0;
  }
  return keys;
}

interface Case {
  n: number;
  pattern: Pattern;
  descending: boolean;
}

class Harness {
  constructor(
    readonly device: GPUDevice,
    readonly sort: RadixSortByKey,
    readonly length: number,
    readonly keys = upload(device, 'test.keys', new Uint32Array(0), length),
    readonly values = upload(device, 'test.values', new Uint32Array(0), length),
    readonly keysOut = upload(device, 'test.keysOut', new Uint32Array(0), length),
    readonly valuesOut = upload(device, 'test.valuesOut', new Uint32Array(0), length),
  ) {}

  /** Sorts one case out of place (or in place) and returns a problem or ''. */
  async run({ n, pattern, descending }: Case, inPlace = false, keyBits = 32): Promise<string> {
    const { device } = this;
    const keys = makeKeys(pattern, n + EXTRA, n, n + (descending ? 1 : 0) + pattern.length * 1000);
    const values = randomU32(n + EXTRA, n + 99);
    device.queue.writeBuffer(this.keys, 0, keys);
    device.queue.writeBuffer(this.values, 0, values);
    poison(device, this.keysOut);
    poison(device, this.valuesOut);
    const count = gpuCount(device, n);
    const encoder = device.createCommandEncoder();
    this.sort.encode(encoder, {
      keys: this.keys,
      values: this.values,
      ...(inPlace ? {} : { keysOut: this.keysOut, valuesOut: this.valuesOut }),
      count,
      descending,
      keyBits,
    });
    device.queue.submit([encoder.finish()]);
    const perm = cpuSortPermutation(keys, n, descending, keyBits);
    // In place: the tail past n keeps the input; out of place: the input is
    // unchanged and the output's tail stays poisoned.
    const ek = inPlace ? keys.slice() : new Uint32Array(n);
    const ev = inPlace ? values.slice() : new Uint32Array(n);
    for (let i = 0; i < n; i++) {
      ek[i] = keys[perm[i]];
      ev[i] = values[perm[i]];
    }
    const outK = await read(device, inPlace ? this.keys : this.keysOut, n + EXTRA);
    const outV = await read(device, inPlace ? this.values : this.valuesOut, n + EXTRA);
    const problems = [diff(outK, ek, 'key'), diff(outV, ev, 'value')];
    if (!inPlace) {
      problems.push(diff(await read(device, this.keys, n + EXTRA), keys, 'input key'));
      problems.push(diff(await read(device, this.keysOut, this.length).then((a) => a.subarray(n + EXTRA)), new Uint32Array(0), 'tail key'));
    }
    count.buffer.destroy();
    const found = problems.filter((p) => p !== '');
    return found.length
      ? `n=${n} ${pattern} ${descending ? 'desc' : 'asc'}${inPlace ? ' in place' : ''} keyBits=${keyBits}: ${found.join('; ')}`
      : '';
  }

  destroy(): void {
    for (const b of [this.keys, this.values, this.keysOut, this.valuesOut]) b.destroy();
  }
}

async function runAll(h: Harness, cases: Case[]): Promise<string[]> {
  const problems: string[] = [];
  for (const c of cases) {
    const p = await h.run(c);
    if (p) problems.push(p);
  }
  return problems;
}

for (const variant of SCAN_VARIANTS)
  describe(`RadixSortByKey, ${variant.name} path`, () => {
    gpuTest('small sizes: every pattern, ascending and descending', async ({ gpu }) => {
      const { device } = gpu;
      const opts = variantOptions(device, variant);
      if (!opts) return;
      const sort = await RadixSortByKey.create(device, { capacity: 65536 + EXTRA, ...opts });
      expect(sort.path).toBe(variant.path);
      expect(sort.subgroups).toBe(variant.subgroups);
      const h = new Harness(device, sort, 65536 + EXTRA);
      const cases: Case[] = [];
      for (const n of SMALL_SIZES)
        for (const pattern of PATTERNS) for (const descending of [false, true]) cases.push({ n, pattern, descending });
      expect(await runAll(h, cases)).toEqual([]);
      h.destroy();
      sort.destroy();
    });

    gpuTest('large sizes', async ({ gpu }) => {
      const { device } = gpu;
      const opts = variantOptions(device, variant);
      if (!opts) return;
      // What a large size adds is many workgroups and digit tables wider than
      // one dispatch row; the patterns and both directions are data, shown at
      // every small size above: here each pattern once, directions alternating
      // (the GPU path, slow on SwiftShader, on its largeSizes).
      const gpuPath = variant.path === 'gpu';
      const [odd, mid, big] = gpuPath ? [...largeSizes('gpu'), 0] : LARGE_SIZES;
      const sort = await RadixSortByKey.create(device, { capacity: Math.max(odd, big) + EXTRA, ...opts });
      const h = new Harness(device, sort, Math.max(odd, big) + EXTRA);
      const cases: Case[] = [];
      // The subgroup variant changes only the digit-table scan (tested on
      // every size by scan.test.ts): one case here.
      // A rerun for another implementation (wgpu): one large case per variant (the unit suite has them all).
      for (const pattern of variant.subgroups || codePathRerun ? PATTERNS.slice(0, 1) : PATTERNS)
        cases.push({ n: mid, pattern, descending: pattern.length % 2 === 0 });
      if (!variant.subgroups && !codePathRerun) cases.push({ n: odd, pattern: 'random', descending: true });
      if (!gpuPath && !codePathRerun) cases.push({ n: big, pattern: 'few', descending: false });
      expect(await runAll(h, cases)).toEqual([]);
      h.destroy();
      sort.destroy();
    });

    gpuTest('in place (even and odd pass counts), fewer key bits, 2D grids, tiny chunks, grow', async ({ gpu }) => {
      const { device } = gpu;
      const opts = variantOptions(device, variant);
      if (!opts) return;
      const problems: string[] = [];
      // Workgroups of 8 (fewer invocations than digits) and 40 (a partial second
      // word in the GPU path's per-digit bitmaps).
      for (const options of [{}, { chunk: 3, maxWorkgroupsPerDimension: 2, workgroupSize: 8 }, { chunk: 5, workgroupSize: 40 }]) {
        const sort = await RadixSortByKey.create(device, { capacity: 10, ...options, ...opts });
        sort.grow(70000);
        expect(sort.capacity).toBe(70000);
        const h = new Harness(device, sort, 70000);
        for (const n of [0, 1, 257, 4095, 65537]) {
          for (const [inPlace, keyBits, descending] of [
            [true, 32, false],
            [true, 12, true],
            [true, 4, false],
            [false, 12, false],
            [false, 1, true],
          ] as const) {
            const p = await h.run({ n, pattern: n % 2 ? 'random' : 'few', descending }, inPlace, keyBits);
            if (p) problems.push(`${JSON.stringify(options)} ${p}`);
          }
        }
        h.destroy();
        sort.destroy();
      }
      expect(problems).toEqual([]);
    });

    gpuTest('the cache update chain, on the GPU only: scan, compact IDs and ages, sort by age oldest first', async ({ gpu }) => {
      const { device } = gpu;
      const opts = variantOptions(device, variant);
      if (!opts) return;
      // Slots with ages; a mask of available slots; their ids sorted by age,
      // descending, with the count known only to the GPU (the scan's total).
      const slots = 300007;
      const ages = randomU32(slots, 77).map((a) => a % 1000);
      const avail = randomMask(slots, 0.4, 78);
      const [scan, compactIds, compact, sort] = await Promise.all([
        ExclusiveScan.create(device, { capacity: slots, ...opts }),
        StreamCompactIds.create(device, opts),
        StreamCompact.create(device, opts),
        RadixSortByKey.create(device, { capacity: slots, ...opts }),
      ]);
      const agesBuf = upload(device, 'ages', ages);
      const availBuf = upload(device, 'avail', avail);
      const offsets = upload(device, 'offsets', new Uint32Array(0), slots);
      const ids = upload(device, 'ids', new Uint32Array(0), slots);
      const keys = upload(device, 'keys', new Uint32Array(0), slots);
      const sortedIds = upload(device, 'sortedIds', new Uint32Array(0), slots);
      const sortedAges = upload(device, 'sortedAges', new Uint32Array(0), slots);
      const counts = upload(device, 'counts', new Uint32Array([slots, 0]));
      const encoder = device.createCommandEncoder();
      const slotCount = { buffer: counts, offset: 0 };
      const availCount = { buffer: counts, offset: 4 };
      scan.encode(encoder, { input: availBuf, output: offsets, count: slotCount, totalOut: availCount });
      compactIds.encode(encoder, { mask: availBuf, offsets, output: ids, count: slotCount });
      compact.encode(encoder, { mask: availBuf, offsets, values: agesBuf, output: keys, count: slotCount });
      sort.encode(encoder, {
        keys,
        values: ids,
        keysOut: sortedAges,
        valuesOut: sortedIds,
        count: availCount,
        descending: true,
        keyBits: 10,
      });
      device.queue.submit([encoder.finish()]);

      const availIds: number[] = [];
      for (let i = 0; i < slots; i++) if (avail[i]) availIds.push(i);
      const stable = availIds.slice().sort((a, b) => ages[b] - ages[a] || a - b);
      expect((await read(device, counts))[1]).toBe(availIds.length);
      expect(diff(await read(device, sortedIds), Uint32Array.from(stable), 'slot')).toBe('');
      expect(
        diff(
          await read(device, sortedAges),
          Uint32Array.from(stable, (s) => ages[s]),
          'age',
        ),
      ).toBe('');
      for (const p of [scan, compactIds, compact, sort]) p.destroy();
    });
  });
