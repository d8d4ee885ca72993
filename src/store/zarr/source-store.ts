// Stores of lossless chunks (the OME-Zarr people publish: blosc, zstd, gzip,
// zlib, lz4, sharding, Zarr v2 or v3; any integer or float type; any chunk
// shape; 3-D or 5-D tczyx). Chunks are decoded by zarrita's codecs on the
// CPU, and the page's own bricks are cut from them: C^3 with C a multiple
// of 4 (the source chunk itself when it is such a cube, else 64^3 made of
// the chunks that overlap it; the finer level's edge when that would not
// nest in its bricks: brickEdge), values as float32 (numpy's astype), padded
// past the array's edge as zfp pads a partial block (so a level's bricks
// hold exactly the blocks of the whole level compressed as one stream, as
// the converter's chunks do). The GPU encodes each brick into its pool slot
// at the level's rate (src/zfp/chunked-volume.ts, layout.arrivesAs
// 'float32'): everything downstream is the zfp store's pipeline.
import type { GetOptions } from '@zarrita/storage';
import * as zarr from 'zarrita';
import { surfaceDimsProblem } from '../../core/limits.ts';
import type { ChunkIndex, ChunkLevelLayout } from '../types.ts';
import { ByteLru } from '../fetch/lru-bytes.ts';
import { brickEdge } from './brick-edge.ts';
import { describeTransportError, StoreError } from './errors.ts';

type Json = Record<string, unknown>;
const isObject = (v: unknown): v is Json => typeof v === 'object' && v !== null && !Array.isArray(v);

/** Rate of stores of lossless chunks when none is asked for (bits per value). */
export const DEFAULT_SOURCE_RATE = 8;
/** A decoded source chunk larger than this is refused (hostile metadata must not allocate). */
const MAX_SOURCE_CHUNK_BYTES = 1 << 30;
const MAX_EDGE = 2 ** 31;
const MAX_BRICKS = 2 ** 26;

/** Value types taken, with what converting them to float32 costs. */
const DTYPES: Record<string, { bytes: number; exact: string }> = {
  uint8: { bytes: 1, exact: 'exact' },
  int8: { bytes: 1, exact: 'exact' },
  uint16: { bytes: 2, exact: 'exact' },
  int16: { bytes: 2, exact: 'exact' },
  uint32: { bytes: 4, exact: 'rounded to 24 significant bits above 2^24' },
  int32: { bytes: 4, exact: 'rounded to 24 significant bits above 2^24' },
  int64: { bytes: 8, exact: 'rounded to 24 significant bits above 2^24' },
  uint64: { bytes: 8, exact: 'rounded to 24 significant bits above 2^24' },
  float32: { bytes: 4, exact: 'exact' },
  float64: { bytes: 8, exact: 'rounded to float32 (24 significant bits, range ±3.4e38)' },
};

/** Bricks of a level side by side along z, as the rate chooser takes a volume. */
export interface RateSample {
  bytes: Uint8Array;
  /** The source's type when float32 holds it exactly and the encoder reads it (8/16-bit integers, float32), else float32. */
  dtype: 'uint8' | 'int8' | 'uint16' | 'int16' | 'float32';
  dims: [number, number, number];
  name: string;
}

/** The sample's bytes in `dtype` (exact: the values came from it). */
export function sampleAs(values: Float32Array, source: string): Pick<RateSample, 'bytes' | 'dtype'> {
  const ctor = { uint8: Uint8Array, int8: Int8Array, uint16: Uint16Array, int16: Int16Array }[source];
  if (!ctor) return { bytes: new Uint8Array(values.buffer, values.byteOffset, values.byteLength), dtype: 'float32' };
  const typed = ctor.from(values);
  return { bytes: new Uint8Array(typed.buffer), dtype: source as RateSample['dtype'] };
}

/** What the Store panel and the record say about a store of lossless chunks. */
export interface SourceInfo {
  /** 'Zarr v2' or 'Zarr v3'. */
  format: string;
  /** Codecs of level 0's chunks, outermost last (e.g. ['bytes', 'zstd'], ['sharding_indexed(bytes, blosc)']). */
  codecs: string[];
  dtype: string;
  /** Level 0's chunk shape in its axis order, with the axes' names. */
  chunkShape: number[];
  axes: string[];
  /** Time point and channel shown, of how many (1 when the array has no such axis). */
  time: { index: number; count: number };
  channel: { index: number; count: number };
  /** How bricks come from chunks at level 0: 'chunks' (each chunk a brick) or 'bricks of 64^3'. */
  bricks: string;
  /** The GPU's rate for the bricks (bits per value). */
  rate: number;
  /** How it was set: asked for (link, panel, --rate), the ranges sidecar's, chosen from the data, or the default. */
  rateHow: 'given' | 'sidecar' | 'chosen' | 'default';
  /** The choice in words (chosen only). */
  rateNote: string | null;
  /** How converting to float32 treats the values. */
  precision: string;
}

/** One level: its source array and how bricks map onto its chunks. */
export interface SourceLevel {
  /** The array's path in the store ("" for a store that is one array). */
  path: string;
  array: zarr.Array<zarr.DataType, zarr.Readable>;
  /** Axis positions of x, y, z in the array's shape. */
  spatial: [number, number, number];
  /** Fixed indices of the other axes (time, channel, ...), by axis position. */
  fixed: Map<number, number>;
  /** Source chunk edges along x, y, z. */
  chunkXYZ: [number, number, number];
  layout: ChunkLevelLayout;
}

/** Names of the codecs in a v3 array's zarr.json or a v2 .zarray, as zarrita's registry knows them. */
export function codecNames(meta: Json, format: 2 | 3): { names: string[]; shown: string[] } {
  if (format === 2) {
    const filters = Array.isArray(meta.filters) ? (meta.filters as Json[]) : [];
    const list = [...filters, ...(isObject(meta.compressor) ? [meta.compressor] : [])];
    const names = list.map((c) => `numcodecs.${String(c.id)}`);
    return { names, shown: list.map((c) => String(c.id)) };
  }
  const names: string[] = [];
  const shown: string[] = [];
  for (const c of (Array.isArray(meta.codecs) ? meta.codecs : []) as Json[]) {
    const name = String(c?.name);
    if (name === 'sharding_indexed') {
      const inner = codecNames((c.configuration ?? {}) as Json, 3);
      names.push(...inner.names);
      shown.push(`sharding_indexed(${inner.shown.join(', ')})`);
    } else {
      names.push(name);
      shown.push(name);
    }
  }
  return { names, shown };
}

/** Throws a StoreError naming the level when its metadata cannot be read here (codec, type, shape). */
export function checkSourceMeta(where: string, meta: Json, format: 2 | 3): void {
  const { names } = codecNames(meta, format);
  const unknown = names.filter((n) => !zarr.registry.has(n) && n !== 'sharding_indexed');
  if (unknown.length > 0) {
    const known = [...new Set([...zarr.registry.keys()].map((k) => k.replace(/^numcodecs\./, '')))]
      .filter((k) => !['zfpy', 'vlen-utf8', 'json2'].includes(k))
      .join(', ');
    throw new StoreError(
      'codec',
      `${where}: its chunks use the codec ${unknown.map((n) => `"${n.replace(/^numcodecs\./, '')}"`).join(', ')}, which this reader does not have (it reads ${known}, and numcodecs.zfpy fixed rate)`,
    );
  }
  const dtype = format === 2 ? String(meta.dtype) : String(meta.data_type);
  const v3 = format === 2 ? v2DtypeName(dtype) : dtype;
  if (!DTYPES[v3]) {
    const what = /complex|c8|c16/.test(v3)
      ? 'complex numbers'
      : /bool|\|b1/.test(v3)
        ? 'booleans'
        : /str|U|S|O|string/.test(v3)
          ? 'strings'
          : v3;
    throw new StoreError(
      'codec',
      `${where}: its values are ${what} (${dtype}); isosurfaces need integer or float values (uint8..uint64, int8..int64, float32, float64)`,
    );
  }
}

function v2DtypeName(d: string): string {
  const m = /^[<>|=]?([uifcbUSOM])(\d+)$/.exec(d);
  if (!m) return d;
  const [, kind, n] = m;
  const bits = Number(n) * 8;
  if (kind === 'u') return `uint${bits}`;
  if (kind === 'i') return `int${bits}`;
  if (kind === 'f') return `float${bits}`;
  if (kind === 'c') return `complex${bits}`;
  if (kind === 'b') return 'bool';
  return d;
}

/** Which axes are x, y, z (OME axes by name, else the last three), and the others' chosen index. */
export function axesOf(
  where: string,
  shape: readonly number[],
  omeAxes: string[] | null,
  choose: { time?: number; channel?: number },
): {
  spatial: [number, number, number];
  fixed: Map<number, number>;
  names: string[];
  time: SourceInfo['time'];
  channel: SourceInfo['channel'];
} {
  const names =
    omeAxes && omeAxes.length === shape.length
      ? omeAxes
      : shape.map((_, i) => ['t', 'c', 'z', 'y', 'x'].slice(-shape.length)[i] ?? `dim${i}`);
  const find = (n: string) => names.indexOf(n);
  let [x, y, z] = [find('x'), find('y'), find('z')];
  if (x < 0 || y < 0 || z < 0 || shape.length < 3) {
    const spatial = omeAxes ? omeAxes.filter((a) => ['x', 'y', 'z'].includes(a)).length : shape.length;
    throw new StoreError(
      'layout',
      `${where}: a ${Math.min(spatial, shape.length)}-D image (shape [${shape.join(', ')}]${omeAxes ? `, axes ${omeAxes.join('')}` : ''}); isosurfaces need a 3-D volume (z, y, x)`,
    );
  }
  if (!omeAxes) [z, y, x] = [shape.length - 3, shape.length - 2, shape.length - 1];
  const fixed = new Map<number, number>();
  const time = { index: 0, count: 1 };
  const channel = { index: 0, count: 1 };
  names.forEach((n, i) => {
    if (i === x || i === y || i === z) return;
    const isTime = n === 't' || n === 'time';
    const isChannel = n === 'c' || n === 'channel';
    const asked = isTime ? choose.time : isChannel ? choose.channel : undefined;
    const index = asked ?? 0;
    if (!Number.isInteger(index) || index < 0 || index >= shape[i])
      throw new StoreError(
        'layout',
        `${where}: ${isTime ? 'time point' : isChannel ? 'channel' : `axis ${n} index`} ${index} is outside 0..${shape[i] - 1}`,
      );
    fixed.set(i, index);
    if (isTime) Object.assign(time, { index, count: shape[i] });
    if (isChannel) Object.assign(channel, { index, count: shape[i] });
  });
  return { spatial: [x, y, z], fixed, names, time, channel };
}

/** The level's layout of bricks (edge: brickEdge) and its source array's axes; throws StoreError on what cannot be read. */
export function sourceLevel(
  path: string,
  where: string,
  array: zarr.Array<zarr.DataType, zarr.Readable>,
  axes: ReturnType<typeof axesOf>,
  rate: number,
  chunkBytesAt: (edge: number, rate: number) => number,
  brick: (chunkXYZ: [number, number, number]) => number = (c) => brickEdge(c, [1, 1, 1]),
): SourceLevel {
  const shape = array.shape;
  const chunks = array.chunks;
  const [ix, iy, iz] = axes.spatial;
  const dims: [number, number, number] = [shape[ix], shape[iy], shape[iz]];
  const chunkXYZ: [number, number, number] = [chunks[ix], chunks[iy], chunks[iz]];
  if (!dims.every((n) => Number.isInteger(n) && n >= 1 && n <= MAX_EDGE))
    throw new StoreError(
      'layout',
      `${where}: shape [${shape.join(', ')}] is not a volume this reader takes (1 to ${MAX_EDGE} voxels per axis)`,
    );
  if (!chunks.every((n) => Number.isInteger(n) && n >= 1))
    throw new StoreError('layout', `${where}: chunk shape [${chunks.join(', ')}] is impossible`);
  const bytes = DTYPES[array.dtype]?.bytes ?? 8;
  const chunkValues = chunks.reduce((a, b) => a * b, 1);
  if (chunkValues * bytes > MAX_SOURCE_CHUNK_BYTES)
    throw new StoreError(
      'layout',
      `${where}: chunks of [${chunks.join(', ')}] ${array.dtype} are ${chunkValues * bytes} bytes decoded, more than ${MAX_SOURCE_CHUNK_BYTES} this reader decodes`,
    );
  const edge = brick(chunkXYZ);
  const chunkGrid: [number, number, number] = [Math.ceil(dims[0] / edge), Math.ceil(dims[1] / edge), Math.ceil(dims[2] / edge)];
  const count = chunkGrid[0] * chunkGrid[1] * chunkGrid[2];
  if (count > MAX_BRICKS)
    throw new StoreError(
      'layout',
      `${where}: ${chunkGrid.join(' x ')} bricks of ${edge}^3; this reader takes at most ${MAX_BRICKS} per level`,
    );
  return {
    path,
    array,
    spatial: axes.spatial,
    fixed: axes.fixed,
    chunkXYZ,
    layout: { dims, chunkEdge: edge, chunkGrid, rate, chunkBytes: chunkBytesAt(edge, rate), name: where, arrivesAs: 'float32' },
  };
}

export function unusableLevel(level: SourceLevel): string | null {
  const tooWide = surfaceDimsProblem(level.layout.dims);
  return tooWide ? `${level.layout.name}: ${tooWide}` : null;
}

export function sourcePrecision(dtype: string): string {
  return DTYPES[dtype]?.exact ?? 'exact';
}

export function sourceBytesPerValue(dtype: string): number {
  return DTYPES[dtype]?.bytes ?? 4;
}

interface DecodedChunk {
  data: ArrayLike<number | bigint>;
  stride: number[];
  /** Where the chosen time point / channel starts in `data`. */
  base: number;
  bytes: number;
}

/** Where bricks come from: a BrickReader here, or a pool of workers running one each (src/store/decode/). */
export interface BrickSource {
  /** Brick `brick` of level `level`: C^3 float32 values (x fastest) as bytes, padded as zfp pads. */
  read(level: number, brick: ChunkIndex, options?: GetOptions): Promise<Uint8Array>;
  /** Source chunks decoded, their decoded bytes, ms from request to decoded; NaN / Inf values replaced (bricks' voxels, padding included). */
  readonly counters: { chunksDecoded: number; bytesDecoded: number; decodeMs: number; nonFinite: number };
  /** Per level, [min, max] of the source values of the bricks read so far. */
  readonly valueRanges: Array<[number, number]>;
  destroy?(): void;
}

/**
 * Reads bricks of source levels: the chunks a brick overlaps, each fetched
 * and decoded once while neighbours need it (an LRU of decoded chunks
 * bounded in bytes; requests of several bricks for one chunk share it).
 */
export class BrickReader implements BrickSource {
  readonly #decoded: ByteLru<string, DecodedChunk>;
  readonly #inFlight = new Map<string, Promise<DecodedChunk>>();
  /** Decoded (not stored) bytes of source chunks read, and how many. */
  readonly counters = { chunksDecoded: 0, bytesDecoded: 0, decodeMs: 0, nonFinite: 0 };
  /** Per level, [min, max] of the source values (as float32) of the bricks read so far; NaN values are skipped. */
  readonly valueRanges: Array<[number, number]>;

  constructor(
    private readonly levels: readonly SourceLevel[],
    cacheBytes = 256 << 20,
  ) {
    this.#decoded = new ByteLru<string, DecodedChunk>(cacheBytes, (c) => c.bytes);
    this.valueRanges = levels.map(() => [Infinity, -Infinity]);
  }

  /** Brick `brick` of level `level`: C^3 float32 values (x fastest) as bytes, padded as zfp pads. */
  async read(level: number, brick: ChunkIndex, options?: GetOptions): Promise<Uint8Array> {
    const L = this.levels[level];
    const { dims, chunkEdge: B, chunkGrid } = L.layout;
    const [gx, gy] = chunkGrid;
    const b = [brick % gx, Math.floor(brick / gx) % gy, Math.floor(brick / (gx * gy))];
    const lo = b.map((v) => v * B);
    const n = lo.map((v, a) => Math.min(B, dims[a] - v)); // valid voxels per axis
    const out = new Float32Array(B * B * B);
    const [cx, cy, cz] = L.chunkXYZ;
    const first = [Math.floor(lo[0] / cx), Math.floor(lo[1] / cy), Math.floor(lo[2] / cz)];
    const last = [Math.floor((lo[0] + n[0] - 1) / cx), Math.floor((lo[1] + n[1] - 1) / cy), Math.floor((lo[2] + n[2] - 1) / cz)];
    const jobs: Promise<void>[] = [];
    for (let kz = first[2]; kz <= last[2]; kz++)
      for (let ky = first[1]; ky <= last[1]; ky++)
        for (let kx = first[0]; kx <= last[0]; kx++) {
          jobs.push(this.#chunk(level, [kx, ky, kz]).then((c) => copyInto(out, B, lo, n, c, [kx * cx, ky * cy, kz * cz], L)));
        }
    await abortable(Promise.all(jobs), options?.signal);
    padLikeZfp(out, B, n);
    // zfp cannot hold NaN or Inf: NaN and -Inf become the brick's smallest finite value, +Inf its largest
    // (in core they become the volume's, which a stream does not know before it has read everything);
    // the range is of the finite values
    let min = Infinity;
    let max = -Infinity;
    let nonFinite = 0;
    for (let i = 0; i < out.length; i++) {
      const v = out[i];
      if (v - v !== 0) nonFinite++;
      else {
        if (v < min) min = v;
        if (v > max) max = v;
      }
    }
    const range = this.valueRanges[level];
    if (nonFinite > 0) {
      // nothing finite: the level's smallest value read so far (0 before any), a constant brick
      const fill = min > max ? (Number.isFinite(range[0]) ? range[0] : 0) : null;
      for (let i = 0; i < out.length; i++) if (out[i] - out[i] !== 0) out[i] = fill ?? (out[i] === Infinity ? max : min);
      this.counters.nonFinite += nonFinite;
    }
    if (min < range[0]) range[0] = min;
    if (max > range[1]) range[1] = max;
    return new Uint8Array(out.buffer);
  }

  // Not aborted with the brick: another brick may wait for the same chunk (the read goes on, the brick's wait ends).
  async #chunk(level: number, k: [number, number, number]): Promise<DecodedChunk> {
    const key = chunkKey(level, k);
    const hit = this.#decoded.get(key);
    if (hit) return hit;
    let p = this.#inFlight.get(key);
    if (!p) {
      p = this.#fetch(level, k).finally(() => this.#inFlight.delete(key));
      this.#inFlight.set(key, p);
    }
    return p;
  }

  async #fetch(level: number, k: [number, number, number]): Promise<DecodedChunk> {
    const L = this.levels[level];
    const coords = new Array<number>(L.array.shape.length).fill(0);
    const chunks = L.array.chunks;
    for (const [axis, index] of L.fixed) coords[axis] = Math.floor(index / chunks[axis]);
    coords[L.spatial[0]] = k[0];
    coords[L.spatial[1]] = k[1];
    coords[L.spatial[2]] = k[2];
    const where = `${L.layout.name} chunk [${coords.join(', ')}]`;
    const t0 = performance.now();
    let got;
    try {
      got = await L.array.getChunk(coords);
    } catch (e) {
      // zarrita's own errors are about the bytes (a codec that fails, metadata that does not fit); the rest is the transport's
      if (zarr.isZarritaError(e))
        throw new StoreError('corrupt', `${where}: does not decode (${(e as Error).message}${causeOf(e)})`, { cause: e });
      throw describeTransportError(e, where);
    }
    const data = got.data as ArrayLike<number | bigint>;
    const expect = chunks.reduce((a, b) => a * b, 1);
    if (!data || data.length !== expect)
      throw new StoreError('corrupt', `${where}: decoded to ${data?.length ?? 0} values, its shape [${chunks.join(', ')}] holds ${expect}`);
    // offset of the fixed axes inside the chunk folded into a view's base
    let base = 0;
    for (const [axis, index] of L.fixed) base += (index % chunks[axis]) * got.stride[axis];
    const bytes = (data as unknown as ArrayBufferView).byteLength ?? data.length * 8;
    const c: DecodedChunk = { data, stride: got.stride.slice(), base, bytes };
    this.counters.chunksDecoded++;
    this.counters.bytesDecoded += bytes;
    this.counters.decodeMs += performance.now() - t0;
    this.#decoded.set(chunkKey(level, k), c);
    return c;
  }
}

/** `p`, or an AbortError as soon as `signal` aborts. */
function abortable<T>(p: Promise<T>, signal?: AbortSignal): Promise<T> {
  if (!signal) return p;
  signal.throwIfAborted();
  return new Promise<T>((resolve, reject) => {
    const onAbort = () => reject(signal.reason ?? new DOMException('aborted', 'AbortError'));
    signal.addEventListener('abort', onAbort, { once: true });
    p.then(resolve, reject).finally(() => signal.removeEventListener('abort', onAbort));
  });
}

const chunkKey = (level: number, k: number[]) => `${level}:${k.join(',')}`;

function causeOf(e: unknown): string {
  const c = (e as { cause?: unknown }).cause;
  return c instanceof Error ? `: ${c.message}` : '';
}

/** Copies the part of a decoded source chunk (origin `o`, level voxels) that falls in the brick (origin `lo`, `n` valid voxels). */
function copyInto(out: Float32Array, B: number, lo: number[], n: number[], c: DecodedChunk, o: number[], L: SourceLevel): void {
  const [ix, iy, iz] = L.spatial;
  const sx = c.stride[ix];
  const sy = c.stride[iy];
  const sz = c.stride[iz];
  const base = c.base;
  const [cx, cy, cz] = L.chunkXYZ;
  const x0 = Math.max(lo[0], o[0]);
  const x1 = Math.min(lo[0] + n[0], o[0] + cx);
  const y0 = Math.max(lo[1], o[1]);
  const y1 = Math.min(lo[1] + n[1], o[1] + cy);
  const z0 = Math.max(lo[2], o[2]);
  const z1 = Math.min(lo[2] + n[2], o[2] + cz);
  const data = c.data;
  const big = typeof data[0] === 'bigint';
  for (let z = z0; z < z1; z++)
    for (let y = y0; y < y1; y++) {
      let src = base + (z - o[2]) * sz + (y - o[1]) * sy + (x0 - o[0]) * sx;
      let dst = x0 - lo[0] + B * (y - lo[1] + B * (z - lo[2]));
      if (big) {
        for (let x = x0; x < x1; x++, src += sx) out[dst++] = Number(data[src] as bigint);
      } else {
        const d = data as ArrayLike<number>;
        for (let x = x0; x < x1; x++, src += sx) out[dst++] = d[src];
      }
    }
}

/**
 * Fills the brick past its `n` valid voxels per axis: inside the partial
 * 4-block as zfp pads it (x, then y, then z; n % 4 = 1: a a a a, 2: a b b a,
 * 3: a b c a), beyond it (blocks no surface reads) with the last valid
 * plane, so the brick's ranges stay those of its values.
 */
export function padLikeZfp(out: Float32Array, B: number, n: number[]): void {
  const from = (p: number, count: number): number => {
    const b = Math.floor(p / 4) * 4;
    if (b >= count) return count - 1;
    const m = count - b; // valid in this block, 1..3
    const q = p - b;
    return b + (q < m ? q : m === 2 && q === 2 ? 1 : 0);
  };
  const [nx, ny, nz] = n;
  if (nx < B)
    for (let z = 0; z < nz; z++)
      for (let y = 0; y < ny; y++) {
        const row = B * (y + B * z);
        for (let x = nx; x < B; x++) out[row + x] = out[row + from(x, nx)];
      }
  if (ny < B)
    for (let z = 0; z < nz; z++)
      for (let y = ny; y < B; y++) out.copyWithin(B * (y + B * z), B * (from(y, ny) + B * z), B * (from(y, ny) + B * z) + B);
  if (nz < B) for (let z = nz; z < B; z++) out.copyWithin(B * B * z, B * B * from(z, nz), B * B * from(z, nz) + B * B);
}
