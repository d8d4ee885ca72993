// `npm run bench:primitives`: elements per second of the GPU primitives
// (exclusive scan, stream compaction, radix sort-by-key) at 2^16, 2^20 and
// 2^24 elements on the adapter at hand, for each kernel family: emulator
// path, GPU path, GPU path with subgroups (where the device has them; the
// scan's and the sort's digit-table scan use them, compaction has no
// workgroup scan and is not repeated); the median of repeats with the first
// discarded. Each figure also gets the bytes it moves per element (by design)
// as bandwidth, and that as a fraction of the device's copyBufferToBuffer
// bandwidth measured in the same run. Writes
// benchmarks/results/primitives-<adapter>.json.
//
//   node benchmarks/run.mjs benchmarks/primitives.ts [--sizes 16,20,24] [--repeats N] [--paths emulator,gpu,gpu+subgroups]
//
// --paths picks the variants (default: all three, or the first two without
// subgroups); the JSON name then ends in -<variants>. Each row says which
// variant `path: 'auto'` picks on this adapter.
import { fileURLToPath } from 'node:url';
import { describeAdapter } from '../src/gpu/device.ts';
import { requestNodeGpu } from '../src/gpu/node-gpu.ts';
import { StreamCompact } from '../src/primitives/compact.ts';
import { choosePath, type PrimitivePath } from '../src/primitives/dispatch-records.ts';
import { ExclusiveScan } from '../src/primitives/scan.ts';
import { RadixSortByKey } from '../src/primitives/sort.ts';
import { printTable, repeat, writeJson, type Stats } from './lib/report.ts';
import { BracketTimer } from './primitives-timing.ts';
import { xorshiftWords } from './lib/random.ts';

function arg(name: string, fallback: string): string {
  const i = process.argv.indexOf(`--${name}`);
  return i >= 0 && process.argv[i + 1] ? process.argv[i + 1] : fallback;
}

const sizes = arg('sizes', '16,20,24')
  .split(',')
  .map((e) => 2 ** Number(e));
const repeatsArg = arg('repeats', '');
const VARIANTS: Record<string, { path: PrimitivePath; subgroups: boolean }> = {
  emulator: { path: 'emulator', subgroups: false },
  gpu: { path: 'gpu', subgroups: false },
  'gpu+subgroups': { path: 'gpu', subgroups: true },
};
const pathsArg = arg('paths', '');
/** Fewer repeats for the big sizes: SwiftShader takes seconds there. */
const repeatsFor = (n: number) => (repeatsArg ? Number(repeatsArg) : n <= 2 ** 16 ? 11 : n <= 2 ** 20 ? 7 : 4);

const gpu = await requestNodeGpu({ label: 'bench.device', onFailure: (f) => console.error(`WebGPU ${f.kind}: ${f.message}`) });
const { device } = gpu;
const adapter = describeAdapter(gpu.adapter);
const timer = new BracketTimer(device);
const maxN = Math.max(...sizes);
console.log(`adapter: ${adapter}\ntiming: ${timer.source}`);
const variants = (pathsArg || Object.keys(VARIANTS).join(',')).split(',').filter((v) => {
  if (!(v in VARIANTS)) throw new Error(`--paths: unknown variant ${v} (emulator, gpu, gpu+subgroups)`);
  if (VARIANTS[v].subgroups && !gpu.features.subgroups) {
    console.log(`${v}: the device has no 'subgroups' feature; skipped`);
    return false;
  }
  return true;
});
// What path: 'auto' picks here (subgroups are then used wherever the device has them).
const autoVariant = choosePath(device, {}) === 'emulator' ? 'emulator' : gpu.features.subgroups ? 'gpu+subgroups' : 'gpu';

function buffer(label: string, data: Uint32Array<ArrayBuffer> | number): GPUBuffer {
  const size = typeof data === 'number' ? data * 4 : data.byteLength;
  const b = device.createBuffer({
    label,
    size: Math.max(4, size),
    usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST,
  });
  if (typeof data !== 'number') device.queue.writeBuffer(b, 0, data);
  return b;
}

// Inputs at the largest size; smaller sizes use their prefixes via the count.
const mask = xorshiftWords(maxN, 1, 2);
const offsets = new Uint32Array(maxN);
let ones = 0;
for (let i = 0; i < maxN; i++) {
  offsets[i] = ones;
  ones += mask[i];
}
const bufs = {
  a: buffer('bench.a', xorshiftWords(maxN, 2)),
  b: buffer('bench.b', xorshiftWords(maxN, 3)),
  c: buffer('bench.c', maxN),
  d: buffer('bench.d', maxN),
  mask: buffer('bench.mask', mask),
  offsets: buffer('bench.offsets', offsets),
};

interface Row {
  primitive: string;
  /** emulator, gpu or gpu+subgroups. */
  variant: string;
  elements: number;
  /** Bytes read and written per element, by design (see README). */
  bytesPerElement: number;
  ms: Stats;
  elementsPerSecond: number;
  gbPerSecond: number;
  fractionOfCopy: number;
}

// Copy bandwidth: copyBufferToBuffer of the largest buffer (read + write).
const copyMs = await repeat(repeatsFor(maxN) + 2, () => timer.time((e) => e.copyBufferToBuffer(bufs.a, 0, bufs.c, 0, maxN * 4)));
const copyGBs = (2 * maxN * 4) / (copyMs.median * 1e6);
console.log(`copyBufferToBuffer ${maxN * 4} bytes: ${copyMs.median.toFixed(3)} ms median, ${copyGBs.toFixed(2)} GB/s (read + write)`);

// Sort: per 4-bit pass, histogram reads keys (4), scatter reads keys and
// values (8) and writes them (8), plus the digit table (16 counts per
// 128-element chunk: written, scanned, read: about 2.5 bytes; far less per
// 2048-element tile on the GPU path).
const sortBytes = 8 * (4 + 16 + 2.5);
const rows: Row[] = [];
for (const variant of variants) {
  const options = VARIANTS[variant];
  const [scan, compact, sort] = await Promise.all([
    ExclusiveScan.create(device, { capacity: maxN, ...options }),
    StreamCompact.create(device, options),
    RadixSortByKey.create(device, { capacity: maxN, ...options }),
  ]);
  const benches: { name: string; bytes: number; record: (e: GPUCommandEncoder, n: number) => void }[] = [
    // Reduce reads the input, scan reads it again and writes the output.
    { name: 'exclusive scan', bytes: 12, record: (e, n) => scan.encode(e, { input: bufs.a, output: bufs.c, count: n }) },
    // Mask read for all; offsets and values read and the value written for the half that is set.
    {
      name: 'stream compaction (50%)',
      bytes: 4 + 0.5 * 12,
      record: (e, n) => compact.encode(e, { mask: bufs.mask, offsets: bufs.offsets, values: bufs.a, output: bufs.c, count: n }),
    },
    {
      name: 'sort-by-key (32-bit keys)',
      bytes: sortBytes,
      record: (e, n) => sort.encode(e, { keys: bufs.a, values: bufs.b, keysOut: bufs.c, valuesOut: bufs.d, count: n }),
    },
  ];
  for (const bench of benches) {
    // Compaction has no workgroup scan: its subgroup variant is the GPU path.
    if (options.subgroups && bench.name.startsWith('stream compaction')) continue;
    for (const n of sizes) {
      const ms = await repeat(repeatsFor(n), () => timer.time((e) => bench.record(e, n)));
      const eps = n / (ms.median / 1e3);
      const gbs = (eps * bench.bytes) / 1e9;
      rows.push({
        primitive: bench.name,
        variant,
        elements: n,
        bytesPerElement: bench.bytes,
        ms,
        elementsPerSecond: eps,
        gbPerSecond: gbs,
        fractionOfCopy: gbs / copyGBs,
      });
      console.log(`  ${bench.name}, ${variant} 2^${Math.log2(n)}: ${ms.median.toFixed(2)} ms`);
    }
  }
  scan.destroy();
  compact.destroy();
  sort.destroy();
}
rows.sort((a, b) => a.primitive.localeCompare(b.primitive) || a.elements - b.elements);

printTable(
  `GPU primitives on ${adapter} (${timer.source}; median of ${sizes
    .map(repeatsFor)
    .map((r) => r - 1)
    .join('/')} runs, first discarded; * = what path 'auto' picks here)`,
  ['primitive', 'path', 'elements', 'median ms', 'elements/s', 'GB/s', 'of copy'],
  rows.map((r) => [
    r.primitive,
    `${r.variant}${r.variant === autoVariant ? ' *' : ''}`,
    `2^${Math.log2(r.elements)}`,
    r.ms.median,
    r.elementsPerSecond,
    r.gbPerSecond,
    `${(100 * r.fractionOfCopy).toFixed(1)}%`,
  ]),
);
console.log(`copy bandwidth ${copyGBs.toFixed(2)} GB/s${gpu.adapter.software ? ' (SwiftShader: CPU memory, not a GPU figure)' : ''}`);

const slug = (gpu.adapter.software ? 'swiftshader' : [gpu.adapter.vendor, gpu.adapter.architecture].filter(Boolean).join('-') || 'gpu')
  .toLowerCase()
  .replace(/[^a-z0-9]+/g, '-');
const suffix = pathsArg ? `-${variants.join('-').replace(/\+/g, '-')}` : '';
writeJson(fileURLToPath(new URL(`./results/primitives-${slug}${suffix}.json`, import.meta.url)), {
  date: new Date().toISOString(),
  adapter: gpu.adapter,
  features: gpu.features,
  autoVariant,
  timing: timer.source,
  copy: { bytes: maxN * 4, ms: copyMs, gbPerSecond: copyGBs },
  rows,
});
for (const b of Object.values(bufs)) b.destroy();
timer.destroy();
device.destroy();
