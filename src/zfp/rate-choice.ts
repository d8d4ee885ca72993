// The compression rate chosen from the data: the smallest whole rate whose
// error on a sample of the volume's blocks stays under a bound that keeps
// isosurfaces faithful. One definition for the page, the CLI, the benchmarks
// and the converter (converter/zfpzarr/rate.py implements the same rule with
// zfpy; tests/unit/zfp/rate-choice.test.ts checks they agree).
//
// The rule (measured: src/zfp/README.md "Rate from the data"):
//  - sample: the volume itself when it has at most CANDIDATE_BLOCKS (32768)
//    blocks (a sub-grid of barely fewer blocks than the volume skips whole
//    planes: ironProt's 17^3 blocks sampled 16^3 missed its centre, RMS 0.14
//    instead of 0.18); otherwise whole 4x4x4 blocks on a regular sub-grid of the volume's
//    complete blocks, at most CANDIDATE_BLOCKS of them (m per axis, the largest
//    m with prod(min(full blocks on the axis, m)) <= CANDIDATE_BLOCKS; the k-th
//    of n picks block floor((k + 1/2) * full / n)), put side by side into a
//    small volume. zfp encodes blocks independently, so each sampled block
//    has exactly the error it has in the whole stream;
//  - measured blocks: the sample's complete blocks whose values are not all
//    equal (structure): constant blocks (the air around a scan, empty
//    space) are exact at any rate and would dilute the error, so a volume
//    padded with empty space gets the rate of its content (issue 37). They
//    are put side by side along x (4k x 4 x 4 voxels), at most SAMPLE_BLOCKS
//    of them (the j-th of SAMPLE_BLOCKS picks structured block
//    floor((j + 1/2) * k / SAMPLE_BLOCKS)). So many candidates are scanned
//    because a scan with 1% of structure leaves ~40 structured blocks of
//    4096, too few to measure (neghip in 256^3 of zeros: rate 9 instead of its
//    own 8; with 32768 candidates, 338 blocks give 8). A sample with no such
//    block is measured whole (nothing there needs a higher rate);
//  - error: root mean square of decoded - source (float32 values) over the
//    measured blocks' voxels;
//  - bound: integer sources (uint8, int8, uint16, int16): 0.15 of one source
//    step (1); float sources: 1e-4 of the sample's value range (max - min,
//    over every sampled block, constant ones included);
//  - rates: 1, 2, ..., 32 bits per value, bisected (the error falls as the
//    rate grows); when 32 does not meet the bound, 32;
//  - cap: with a stream budget, the largest whole rate whose stream fits it,
//    when the chosen one does not (the message says what that costs).
import type { DType } from '../core/dtype.ts';
import { DTYPE_BYTES } from '../core/dtype.ts';
import { formatDims, type Dims } from '../core/naming.ts';
import type { ZfpEncoder } from './encoder.ts';
import { planZfpStream } from './format.ts';
import type { StreamError, ZfpErrorMeter } from './stream-error.ts';

/** Structured blocks measured, at most (262,144 voxels encoded per trial). */
export const SAMPLE_BLOCKS = 4096;
/** Blocks scanned for structure, at most (2 M voxels); volumes of at most this many blocks are their own sample. */
export const CANDIDATE_BLOCKS = 32768;
/** Volumes of at most this many blocks (1 M voxels) are their own sample whatever the sub-grid's size. */
export const WHOLE_BLOCKS = 16384;
/** Integer sources: the RMS error allowed, in source steps. */
export const INTEGER_RMS_BOUND = 0.15;
/** Float sources: the RMS error allowed, as a fraction of the sample's value range. */
export const FLOAT_RMS_BOUND = 1e-4;
export const MIN_RATE = 1;
export const MAX_RATE = 32;

export function isIntegerType(dtype: DType): boolean {
  return !dtype.startsWith('float');
}

/** Where the sample's blocks come from: per axis, the first voxel of each sampled block (or the whole axis). */
export interface SampleGrid {
  /** Per axis (x, y, z): voxel starts of the sampled blocks. */
  starts: [number[], number[], number[]];
  /** The sample volume's dimensions. */
  dims: Dims;
  /** True when the sample is the whole volume. */
  whole: boolean;
  blocks: number;
}

/** The sample of a volume of `dims` (see the rule above). */
export function sampleGrid(dims: Dims, maxBlocks = CANDIDATE_BLOCKS, wholeBlocks = WHOLE_BLOCKS): SampleGrid {
  const grid = dims.map((n) => Math.ceil(n / 4));
  if (grid[0] * grid[1] * grid[2] <= Math.max(maxBlocks, wholeBlocks)) {
    const starts = dims.map((n) => Array.from({ length: Math.ceil(n / 4) }, (_, i) => 4 * i)) as SampleGrid['starts'];
    return { starts, dims: [...dims], whole: true, blocks: grid[0] * grid[1] * grid[2] };
  }
  // An axis shorter than a block is taken whole (its blocks are padded as in the stream).
  const full = dims.map((n) => Math.max(1, Math.floor(n / 4)));
  let m = 1;
  while (full.reduce((p, f) => p * Math.min(f, m + 1), 1) <= maxBlocks && full.some((f) => f > m)) m++;
  const starts = full.map((f) => {
    const n = Math.min(f, m);
    return Array.from({ length: n }, (_, k) => 4 * Math.floor(((k + 0.5) * f) / n));
  }) as SampleGrid['starts'];
  const sampleDims = starts.map((s, a) => (dims[a] < 4 ? dims[a] : 4 * s.length)) as Dims;
  return { starts, dims: sampleDims, whole: false, blocks: starts[0].length * starts[1].length * starts[2].length };
}

/** The sample's bytes (same type as the volume's), its blocks side by side as the grid places them. */
export function gatherSample(bytes: Uint8Array, dtype: DType, dims: Dims, grid: SampleGrid): Uint8Array {
  if (grid.whole) return bytes;
  const size = DTYPE_BYTES[dtype];
  const [sx, sy, sz] = grid.dims;
  const out = new Uint8Array(sx * sy * sz * size);
  const [xs, ys, zs] = grid.starts;
  const runX = Math.min(4, dims[0]);
  const runY = Math.min(4, dims[1]);
  const runZ = Math.min(4, dims[2]);
  for (let kz = 0; kz < zs.length; kz++)
    for (let z = 0; z < runZ; z++)
      for (let ky = 0; ky < ys.length; ky++)
        for (let y = 0; y < runY; y++) {
          const srcRow = (zs[kz] + z) * dims[1] * dims[0] + (ys[ky] + y) * dims[0];
          const dstRow = (kz * runZ + z) * sy * sx + (ky * runY + y) * sx;
          for (let kx = 0; kx < xs.length; kx++) {
            const from = (srcRow + xs[kx]) * size;
            out.set(bytes.subarray(from, from + runX * size), (dstRow + kx * runX) * size);
          }
        }
  return out;
}

/** The sample's values as float32 (numpy's astype; float64 rounded), x fastest. */
function valuesOf(bytes: Uint8Array, dtype: DType): Float32Array {
  if (dtype === 'float32' && bytes.byteOffset % 4 === 0) return new Float32Array(bytes.buffer, bytes.byteOffset, bytes.byteLength / 4);
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const n = bytes.byteLength / DTYPE_BYTES[dtype];
  const out = new Float32Array(n);
  for (let i = 0; i < n; i++) out[i] = readValue(view, dtype, i);
  return out;
}

function readValue(view: DataView, dtype: DType, i: number): number {
  switch (dtype) {
    case 'uint8':
      return view.getUint8(i);
    case 'int8':
      return view.getInt8(i);
    case 'uint16':
      return view.getUint16(2 * i, true);
    case 'int16':
      return view.getInt16(2 * i, true);
    case 'float32':
      return view.getFloat32(4 * i, true);
    default:
      return Math.fround(view.getFloat64(8 * i, true));
  }
}

/** The blocks the rule measures: the sample's complete blocks whose values are not all equal, side by side along x. */
export interface MeasuredBlocks {
  /** Their values in the sample's type, a volume of `dims`. */
  bytes: Uint8Array;
  dims: Dims;
  blocks: number;
}

/** The sample's structured blocks (see the rule above), or null when it has none. */
export function structuredBlocks(sample: Uint8Array, dtype: DType, dims: Dims, maxBlocks = SAMPLE_BLOCKS): MeasuredBlocks | null {
  const [X, Y, Z] = dims;
  const values = valuesOf(sample, dtype);
  const size = DTYPE_BYTES[dtype];
  const picked: number[] = [];
  for (let bz = 0; bz + 4 <= Z; bz += 4)
    for (let by = 0; by + 4 <= Y; by += 4)
      for (let bx = 0; bx + 4 <= X; bx += 4) {
        const first = values[bx + X * (by + Y * bz)];
        let constant = true;
        for (let z = 0; z < 4 && constant; z++)
          for (let y = 0; y < 4 && constant; y++)
            for (let x = 0; x < 4; x++)
              if (values[bx + x + X * (by + y + Y * (bz + z))] !== first) {
                constant = false;
                break;
              }
        if (!constant) picked.push(bx + X * (by + Y * bz));
      }
  if (picked.length === 0) return null;
  const k = Math.min(picked.length, maxBlocks);
  const kept = k === picked.length ? picked : Array.from({ length: k }, (_, j) => picked[Math.floor(((j + 0.5) * picked.length) / k)]);
  const out = new Uint8Array(64 * k * size);
  const W = 4 * k;
  kept.forEach((origin, j) => {
    for (let z = 0; z < 4; z++)
      for (let y = 0; y < 4; y++) {
        const from = (origin + X * (y + Y * z)) * size;
        out.set(sample.subarray(from, from + 4 * size), (4 * j + W * (y + 4 * z)) * size);
      }
  });
  return { bytes: out, dims: [W, 4, 4], blocks: k };
}

/** The sample's value range as float32 values (the encoder's view of them). */
export function valueRange(bytes: Uint8Array, dtype: DType): [number, number] {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const n = bytes.byteLength / DTYPE_BYTES[dtype];
  let lo = Infinity;
  let hi = -Infinity;
  for (let i = 0; i < n; i++) {
    const v = readValue(view, dtype, i);
    if (v < lo) lo = v;
    if (v > hi) hi = v;
  }
  return [lo, hi];
}

export interface ErrorBound {
  /** Largest RMS error allowed (in the data's units). */
  rms: number;
  /** How it was set, e.g. "0.15 of a source step" or "1e-4 of the value range 0 .. 272.5". */
  rule: string;
}

/** The bound for a sample of `dtype` (its bytes for the value range of floats). */
export function errorBound(dtype: DType, sample: Uint8Array): ErrorBound {
  if (isIntegerType(dtype)) return { rms: INTEGER_RMS_BOUND, rule: `${INTEGER_RMS_BOUND} of a source step (${dtype})` };
  const [lo, hi] = valueRange(sample, dtype);
  const range = hi - lo;
  return { rms: FLOAT_RMS_BOUND * range, rule: `${FLOAT_RMS_BOUND} of the sampled value range ${fmt(lo)} .. ${fmt(hi)} (${dtype})` };
}

export interface RateTrial {
  rate: number;
  rms: number;
  maxAbs: number;
}

export interface RateChoice {
  /** The rate the volume is compressed at. */
  rate: number;
  /**
   * chosen: the smallest rate meeting the bound; unmet: no rate up to 32 does (32 is used);
   * capped: the chosen one did not fit the stream budget (the largest that fits is used);
   * given: the user's rate (the bound is still reported).
   */
  how: 'chosen' | 'unmet' | 'capped' | 'given';
  bound: ErrorBound;
  /** The smallest rate meeting the bound (when one was searched for and found). */
  faithfulRate?: number;
  /** The sample's error at `rate` (what the choice used). */
  sample: RateTrial;
  /** Blocks the error was measured on: the sample's structured blocks (or all of them when none is). */
  sampleBlocks: number;
  /** Blocks sampled; `structured`: whether only the structured ones were measured. */
  candidateBlocks: number;
  structured: boolean;
  /** Every rate tried, in order. */
  trials: RateTrial[];
  /** Wall time of the choice (sample gathering and GPU trials). */
  ms: number;
  /** The whole stream's error at `rate`, when the volume has been compressed (compressMeasured). */
  stream?: StreamError;
  /** For the user when the rate was lowered to fit, or no rate met the bound. */
  warning?: string;
}

export interface ChooseRateOptions {
  /** The user's rate: no search, its error is measured. */
  rate?: number;
  /** Largest stream (bytes, with header) the rate may make. */
  maxStreamBytes?: number;
  fileName?: string;
}

/** Stream bytes (with header) of `dims` at `rate`. */
export function streamBytesAt(dims: Dims, rate: number): number {
  return planZfpStream('volume.raw', dims, rate, true).paddedBytes;
}

/** Chooses the rate of a volume held on the CPU (see the rule above), trying candidate rates on a sample on the GPU. */
export async function chooseRate(
  encoder: ZfpEncoder,
  meter: ZfpErrorMeter,
  bytes: Uint8Array,
  dtype: DType,
  dims: Dims,
  opts: ChooseRateOptions = {},
): Promise<RateChoice> {
  const t0 = performance.now();
  const grid = sampleGrid(dims);
  const sample = gatherSample(bytes, dtype, dims, grid);
  const bound = errorBound(dtype, sample);
  const structured = structuredBlocks(sample, dtype, grid.dims);
  const measured: MeasuredBlocks = structured ?? { bytes: sample, dims: grid.dims, blocks: grid.blocks };
  const trials: RateTrial[] = [];
  const trial = async (rate: number): Promise<RateTrial> => {
    const known = trials.find((t) => t.rate === rate);
    if (known) return known;
    const { stream, error } = await encoder.compressMeasured(measured.bytes, dtype, measured.dims, rate, meter, {
      header: false,
      fileName: `${opts.fileName ?? 'sample'}_${formatDims(measured.dims)}_${dtype}.raw`,
    });
    stream.destroy();
    const t = { rate, rms: error.rms, maxAbs: error.maxAbs };
    trials.push(t);
    return t;
  };
  const meets = (t: RateTrial) => t.rms <= bound.rms;
  const done = (rate: number, how: RateChoice['how'], faithfulRate?: number, warning?: string): RateChoice => ({
    rate,
    how,
    bound,
    ...(faithfulRate !== undefined ? { faithfulRate } : {}),
    sample: trials.find((t) => t.rate === rate)!,
    sampleBlocks: measured.blocks,
    candidateBlocks: grid.blocks,
    structured: structured !== null,
    trials,
    ms: performance.now() - t0,
    ...(warning ? { warning } : {}),
  });

  if (opts.rate !== undefined) {
    await trial(opts.rate);
    return done(opts.rate, 'given');
  }
  let lo = MIN_RATE;
  let hi = MAX_RATE;
  while (lo < hi) {
    const mid = (lo + hi) >> 1;
    if (meets(await trial(mid))) hi = mid;
    else lo = mid + 1;
  }
  const faithful = await trial(hi);
  const name = opts.fileName ?? 'the volume';
  if (!meets(faithful) && hi === MAX_RATE) {
    return done(
      hi,
      'unmet',
      undefined,
      `${name}: no rate up to ${MAX_RATE} keeps the sampled RMS error under ${fmt(bound.rms)} (${bound.rule}); compressed at ${MAX_RATE}, RMS error ${fmt(faithful.rms)}`,
    );
  }
  const budget = opts.maxStreamBytes;
  if (budget !== undefined && streamBytesAt(dims, hi) > budget) {
    let fit = hi - 1;
    while (fit >= MIN_RATE && streamBytesAt(dims, fit) > budget) fit--;
    if (fit < MIN_RATE)
      throw new RangeError(
        `${name}: even rate ${MIN_RATE} makes a ${fmtBytes(streamBytesAt(dims, MIN_RATE))} stream, over the stream budget of ${fmtBytes(budget)}`,
      );
    const capped = await trial(fit);
    return done(
      fit,
      'capped',
      hi,
      `${name}: rate ${hi} (RMS error ${fmt(faithful.rms)}, ${bound.rule}) makes a ${fmtBytes(streamBytesAt(dims, hi))} stream, over the stream budget of ${fmtBytes(budget)}: compressed at rate ${fit} instead, RMS error ${fmt(capped.rms)} (${fmt(capped.rms / bound.rms)} times the bound): expect small spurious triangles and bumps near the isovalue`,
    );
  }
  return done(hi, 'chosen', hi);
}

/** One line on the choice, e.g. "rate 10 chosen from the data: RMS error 0.12 <= 0.15 of a source step (int16), 4096 sampled blocks, 6 rates tried in 41 ms". */
export function describeRateChoice(c: RateChoice): string {
  const whole = c.stream ? `; whole stream: RMS ${fmt(c.stream.rms)}, max ${fmt(c.stream.maxAbs)}` : '';
  const blocks = c.structured ? `${c.sampleBlocks} structured of ${c.candidateBlocks} sampled blocks` : `${c.sampleBlocks} sampled blocks`;
  const sampled = `${blocks}, ${c.trials.length} rate${c.trials.length === 1 ? '' : 's'} tried in ${c.ms.toFixed(0)} ms`;
  switch (c.how) {
    case 'given':
      return `rate ${c.rate} as given: sampled RMS error ${fmt(c.sample.rms)} (bound for faithful surfaces ${fmt(c.bound.rms)}: ${c.bound.rule})${whole}`;
    case 'chosen':
      return `rate ${c.rate} chosen from the data: sampled RMS error ${fmt(c.sample.rms)} <= ${fmt(c.bound.rms)} (${c.bound.rule}), ${sampled}${whole}`;
    case 'capped':
      return `rate ${c.rate} (lowered from ${c.faithfulRate} to fit the stream budget): sampled RMS error ${fmt(c.sample.rms)} > ${fmt(c.bound.rms)} (${c.bound.rule}), ${sampled}${whole}`;
    case 'unmet':
      return `rate ${c.rate}: no rate meets ${fmt(c.bound.rms)} (${c.bound.rule}); sampled RMS error ${fmt(c.sample.rms)}, ${sampled}${whole}`;
  }
}

/** The CLI record's `rateError` (JSON). */
export function rateErrorRecord(c: RateChoice): Record<string, unknown> {
  return {
    how: c.how,
    bound: c.bound.rms,
    rule: c.bound.rule,
    sampleRms: c.sample.rms,
    sampleMax: c.sample.maxAbs,
    sampleBlocks: c.sampleBlocks,
    candidateBlocks: c.candidateBlocks,
    structured: c.structured,
    ...(c.stream ? { rms: c.stream.rms, max: c.stream.maxAbs } : {}),
    ...(c.faithfulRate !== undefined ? { faithfulRate: c.faithfulRate } : {}),
    trials: c.trials,
    ms: c.ms,
  };
}

function fmt(v: number): string {
  if (v === 0) return '0';
  const a = Math.abs(v);
  return a >= 1000 || a < 0.01 ? v.toExponential(2) : String(Number(v.toPrecision(3)));
}

function fmtBytes(b: number): string {
  return b >= 2 ** 30 ? `${(b / 2 ** 30).toFixed(2)} GiB` : `${(b / 2 ** 20).toFixed(1)} MiB`;
}
