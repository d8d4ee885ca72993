// bench:gpu's primitives: exclusive scan, stream compaction (half the
// elements kept) and radix sort-by-key (32-bit keys, u32 values), at the
// plan's sizes (2^20 .. 2^26 on a GPU), on the GPU kernel family with and
// without subgroups (the emulator family is SwiftShader's; bench:primitives
// measures it). GPU time bracketed by timestamps (BracketTimer), median of
// the repeats after a discarded first. At the largest size each output is
// read back and checked against a CPU reference: the scan's sums, the
// compaction's kept values in order, and for the sort: keys ascending, each
// output pair an input pair, ties in input order (a stable sort), so the
// output equals a stable CPU sort's.
import { readU32 } from '../../src/gpu/buffers.ts';
import { StreamCompact } from '../../src/primitives/compact.ts';
import { choosePath } from '../../src/primitives/dispatch-records.ts';
import { ExclusiveScan } from '../../src/primitives/scan.ts';
import { RadixSortByKey } from '../../src/primitives/sort.ts';
import { repeat } from '../lib/report.ts';
import { BracketTimer } from '../primitives-timing.ts';
import type { BenchRun } from './context.ts';
import { xorshiftWords } from '../lib/random.ts';

const SECTION = 'primitives';

export async function primitivesSection(run: BenchRun): Promise<unknown> {
  const { device, features } = run.gpu;
  const sizes = run.plan.primitiveExponents.map((e) => 2 ** e);
  const maxN = Math.max(...sizes);
  const timer = new BracketTimer(device);
  const usage = GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST;
  const made: GPUBuffer[] = [];
  const buffer = (label: string, data: Uint32Array<ArrayBuffer> | number) => {
    const b = device.createBuffer({ label, size: Math.max(4, typeof data === 'number' ? data * 4 : data.byteLength), usage });
    if (typeof data !== 'number') device.queue.writeBuffer(b, 0, data);
    made.push(b);
    return b;
  };
  const keys = xorshiftWords(maxN, 2);
  const iota = Uint32Array.from({ length: maxN }, (_, i) => i);
  const mask = xorshiftWords(maxN, 1, 2);
  const offsets = new Uint32Array(maxN);
  for (let i = 0, ones = 0; i < maxN; i++) {
    offsets[i] = ones;
    ones += mask[i];
  }
  const bufs = {
    keys: buffer('benchGpu.keys', keys),
    values: buffer('benchGpu.values', iota),
    out: buffer('benchGpu.out', maxN),
    outValues: buffer('benchGpu.outValues', maxN),
    mask: buffer('benchGpu.mask', mask),
    offsets: buffer('benchGpu.offsets', offsets),
  };
  // what path 'auto' picks on this adapter
  const auto = choosePath(device, {}) === 'emulator' ? 'emulator' : features.subgroups ? 'gpu+subgroups' : 'gpu';
  const variants = [
    { name: 'gpu', path: 'gpu' as const, subgroups: false },
    ...(features.subgroups ? [{ name: 'gpu+subgroups', path: 'gpu' as const, subgroups: true }] : []),
  ];
  if (!features.subgroups) run.notes.push("primitives: the device has no 'subgroups' feature; only the plain GPU kernels ran");
  const rows: (string | number)[][] = [];
  const records: unknown[] = [];
  try {
    for (const v of variants) {
      const opts = { path: v.path, subgroups: v.subgroups };
      const [scan, compact, sort] = await Promise.all([
        ExclusiveScan.create(device, { capacity: maxN, ...opts }),
        StreamCompact.create(device, opts),
        RadixSortByKey.create(device, { capacity: maxN, ...opts }),
      ]);
      const benches = [
        {
          name: 'exclusive scan',
          record: (e: GPUCommandEncoder, n: number) => scan.encode(e, { input: bufs.keys, output: bufs.out, count: n }),
        },
        {
          name: 'stream compaction (50%)',
          record: (e: GPUCommandEncoder, n: number) =>
            compact.encode(e, { mask: bufs.mask, offsets: bufs.offsets, values: bufs.keys, output: bufs.out, count: n }),
        },
        {
          name: 'radix sort-by-key (32-bit)',
          record: (e: GPUCommandEncoder, n: number) =>
            sort.encode(e, { keys: bufs.keys, values: bufs.values, keysOut: bufs.out, valuesOut: bufs.outValues, count: n }),
        },
      ];
      for (const b of benches) {
        for (const n of sizes) {
          await run.warmUp((e) => b.record(e, n));
          const ms = await repeat(run.plan.primitiveRepeats + 1, () => timer.time((e) => b.record(e, n)));
          const geps = n / (ms.median / 1e3) / 1e9;
          run.figure(SECTION, `${b.name}, ${v.name}, 2^${Math.log2(n)}: G elements/s`, geps, 'G elements/s');
          rows.push([b.name, `${v.name}${v.name === auto ? ' *' : ''}`, `2^${Math.log2(n)}`, ms.median, geps]);
          records.push({ primitive: b.name, variant: v.name, elements: n, ms, gElementsPerSecond: geps });
          console.log(`  ${b.name}, ${v.name}, 2^${Math.log2(n)}: ${ms.median.toFixed(3)} ms, ${geps.toFixed(3)} G elements/s`);
          if (n === maxN || run.plan.smoke) await checkOutput(run, b.name, v.name, n, device, bufs, keys, mask, offsets);
        }
      }
      scan.destroy();
      compact.destroy();
      sort.destroy();
    }
  } finally {
    for (const b of made) b.destroy();
    timer.destroy();
  }
  run.table({
    title: `GPU primitives (${timer.source}; median of ${run.plan.primitiveRepeats} after a discarded first; * = the path 'auto' picks)`,
    header: ['primitive', 'path', 'elements', 'median ms', 'G elements/s'],
    rows,
  });
  return { autoVariant: auto, timing: timer.source, records };
}

async function checkOutput(
  run: BenchRun,
  primitive: string,
  variant: string,
  n: number,
  device: GPUDevice,
  bufs: Record<'keys' | 'values' | 'out' | 'outValues' | 'mask' | 'offsets', GPUBuffer>,
  keys: Uint32Array,
  mask: Uint32Array,
  offsets: Uint32Array,
): Promise<void> {
  const name = `${primitive}, ${variant}, 2^${Math.log2(n)} equals the CPU reference`;
  const out = await readU32(device, bufs.out, 0, n);
  let bad = -1;
  if (primitive.startsWith('exclusive scan')) {
    let sum = 0;
    for (let i = 0; i < n && bad < 0; i++) {
      if (out[i] !== sum >>> 0) bad = i;
      sum = (sum + keys[i]) >>> 0;
    }
    run.check(SECTION, name, bad < 0, bad < 0 ? `${n} prefix sums (mod 2^32)` : `first difference at ${bad}`);
  } else if (primitive.startsWith('stream compaction')) {
    let kept = 0;
    for (let i = 0; i < n && bad < 0; i++) {
      if (mask[i] === 1) {
        if (out[offsets[i]] !== keys[i]) bad = i;
        kept++;
      }
    }
    run.check(SECTION, name, bad < 0, bad < 0 ? `${kept} of ${n} kept, in order` : `element ${bad} misplaced`);
  } else {
    const values = await readU32(device, bufs.outValues, 0, n);
    const seen = new Uint8Array(n);
    for (let i = 0; i < n && bad < 0; i++) {
      const from = values[i];
      if (from >= n || seen[from] || keys[from] !== out[i]) bad = i;
      else if (i > 0 && (out[i - 1] > out[i] || (out[i - 1] === out[i] && values[i - 1] > from))) bad = i;
      else seen[from] = 1;
    }
    run.check(SECTION, name, bad < 0, bad < 0 ? `${n} pairs: keys ascending, a permutation, ties stable` : `order broken at ${bad}`);
  }
}
