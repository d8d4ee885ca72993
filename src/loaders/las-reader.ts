// One LAS/LAZ file through LASzip compiled to WebAssembly (wasm/las): the
// module, the header checks and the chunked point reader (LasReader).
// Whole clouds: las.ts (which re-exports this).
import createLasModule, { type LasWasm } from '../../wasm/dist/las.js';
import { copyIntoHeap, describeWasmFailure, instantiateWasm, ptr, streamIntoHeap, WasmSlot } from './wasm-module.ts';

export type Vec3 = [number, number, number];

export interface LasHeader {
  pointCount: number;
  /** "1.2", "1.4", ... */
  version: string;
  pointFormat: number;
  pointRecordLength: number;
  compressed: boolean;
  scale: Vec3;
  offset: Vec3;
  /** Bounds stored in the header (float64). */
  bounds: { min: Vec3; max: Vec3 };
  /** Positions are relative to this point (the centre of `bounds`). */
  centre: Vec3;
  hasRGB: boolean;
  hasGpsTime: boolean;
  vlrCount: number;
  offsetToPointData: number;
  systemIdentifier: string;
  generatingSoftware: string;
}

/** Which per-point arrays to decode. */
export interface LasFields {
  /** float32 x, y, z relative to `header.centre`. */
  positions?: boolean;
  /** uint16 r, g, b (only when the format has RGB). */
  rgb?: boolean;
  intensity?: boolean;
  classification?: boolean;
  /** The raw int32 X, Y, Z (scaled = X * scale + offset, in float64). */
  xyz?: boolean;
  /** The point records in uncompressed LAS layout (`pointRecordLength` bytes each). */
  records?: boolean;
}

export interface LasChunk {
  /** Index of the first point of the chunk. */
  start: number;
  count: number;
  positions?: Float32Array;
  rgb?: Uint16Array;
  intensity?: Uint16Array;
  classification?: Uint8Array;
  xyz?: Int32Array;
  records?: Uint8Array;
}

/** A file that is not a readable LAS/LAZ file; the message names the file. */
export class LasError extends Error {
  constructor(
    readonly fileName: string,
    readonly reason: string,
  ) {
    super(`${fileName}: ${reason}`);
    this.name = 'LasError';
  }
}

const slot = new WasmSlot(() => instantiateWasm(createLasModule, new URL('../../wasm/dist/las.wasm', import.meta.url), 'LAS/LAZ'));

/** The LASzip module (instantiated once per page or process; replaced after it failed on a file). */
export function loadLasWasm(): Promise<LasWasm> {
  return slot.get();
}

/** A failure inside the module (trap, escaped exception): the module is replaced, the file rejected. */
function moduleFailure(m: LasWasm, fileName: string, e: unknown): LasError {
  if (e instanceof LasError) return e;
  const what = describeWasmFailure(e);
  slot.discard(m, `${fileName}: ${what}`);
  return new LasError(fileName, `the file is corrupt in a way the LAS/LAZ decoder could not handle (${what})`);
}

const INFO_FIELDS = 28;
const DEFAULT_CHUNK = 1 << 16;
/** Scratch memory for one chunk in the Wasm heap: chunks of long records are shortened to fit. */
const MAX_CHUNK_BYTES = 64 << 20;
/** The most points loadPointCloud holds in memory (21 bytes each: about 1 GiB). */
export const MAX_CLOUD_POINTS = 50_000_000;

function readHeader(m: LasWasm, handle: number): LasHeader {
  const info = ptr(m._malloc(INFO_FIELDS * 8));
  if (info === 0) throw new Error('out of WebAssembly memory');
  try {
    m._las_info(handle, info);
    const v = new Float64Array(m.HEAPU8.buffer, info, INFO_FIELDS).slice();
    const v3 = (i: number): Vec3 => [v[i], v[i + 1], v[i + 2]];
    return {
      pointCount: v[0],
      version: `${v[1]}.${v[2]}`,
      pointFormat: v[3],
      pointRecordLength: v[4],
      compressed: v[5] === 1,
      scale: v3(6),
      offset: v3(9),
      bounds: { min: v3(12), max: v3(15) },
      centre: v3(18),
      hasRGB: v[21] === 1,
      hasGpsTime: v[22] === 1,
      vlrCount: v[23],
      offsetToPointData: v[24],
      systemIdentifier: m.UTF8ToString(ptr(m._las_header_string(handle, 0))).trim(),
      generatingSoftware: m.UTF8ToString(ptr(m._las_header_string(handle, 1))).trim(),
    };
  } finally {
    m._free(info);
  }
}

/** The C API checks these already; a second look costs nothing and guards the TS side on its own. */
function checkHeader(h: LasHeader, fileName: string): void {
  if (!Number.isSafeInteger(h.pointCount) || h.pointCount < 0)
    throw new LasError(fileName, `corrupt header: impossible point count ${h.pointCount}`);
  for (const [a, v] of h.scale.entries()) {
    if (!Number.isFinite(v) || v === 0)
      throw new LasError(fileName, `corrupt header: the ${'xyz'[a]} scale factor is ${v} (it must be a finite, non-zero number)`);
  }
  if (!(h.pointRecordLength > 0)) throw new LasError(fileName, 'corrupt header: the point record length is 0');
}

function closeQuietly(m: LasWasm, handle: number, fileName: string): void {
  try {
    m._las_close(handle);
  } catch (e) {
    moduleFailure(m, fileName, e);
  }
}

/** An open LAS/LAZ file in the Wasm heap. Call close() when done. */
export class LasReader {
  private handle: number;
  private nextPoint = 0;
  private outside = 0;
  private scratch: { capacity: number; fields: Required<LasFields>; ptrs: Record<keyof LasFields, number> } | undefined;

  private constructor(
    private readonly m: LasWasm,
    handle: number,
    readonly fileName: string,
    readonly header: LasHeader,
  ) {
    this.handle = handle;
  }

  /**
   * Opens `bytes`, or a Blob/File streamed straight into the heap (the file's
   * only copy). Throws LasError for bad files.
   */
  static async open(bytes: Uint8Array | Blob, fileName: string, onRead?: (done: number, total: number) => void): Promise<LasReader> {
    const m = await loadLasWasm();
    const size = bytes instanceof Uint8Array ? bytes.byteLength : bytes.size;
    if (size > 0xffffffff) throw new LasError(fileName, 'files over 4 GiB do not fit in WebAssembly memory');
    let data: number;
    try {
      data = bytes instanceof Uint8Array ? copyIntoHeap(m, bytes, fileName) : await streamIntoHeap(m, bytes, fileName, onRead);
    } catch (e) {
      throw new LasError(fileName, (e as Error).message.replace(`${fileName}: `, ''));
    }
    // las_open owns `data` from here on, also when it fails.
    let handle = 0;
    let header: LasHeader;
    try {
      handle = ptr(m._las_open(data, size));
      if (handle === 0) throw new LasError(fileName, 'out of WebAssembly memory');
      const error = m.UTF8ToString(ptr(m._las_error(handle)));
      if (error) throw new LasError(fileName, error);
      header = readHeader(m, handle);
    } catch (e) {
      // A module that failed is not touched again (its heap may be corrupt).
      if (handle !== 0 && e instanceof LasError) closeQuietly(m, handle, fileName);
      throw moduleFailure(m, fileName, e);
    }
    checkHeader(header, fileName);
    return new LasReader(m, handle, fileName, header);
  }

  get pointsRead(): number {
    return this.nextPoint;
  }

  get closed(): boolean {
    return this.handle === 0;
  }

  /**
   * What is wrong with the file without making it unreadable, for the page
   * and the CLI to show: points outside the header's bounds, bounds that are
   * not numbers. Grows as points are read.
   */
  get warnings(): string[] {
    const h = this.header;
    if (this.outside < 0) {
      return h.pointCount > 0
        ? [
            `${this.fileName}: the header's bounds are not valid (not finite, or min above max: ${JSON.stringify(h.bounds)}); the points are shown around the header's offsets`,
          ]
        : [];
    }
    if (this.outside === 0) return [];
    return [
      `${this.fileName}: ${this.outside.toLocaleString('en-US')} of ${this.nextPoint.toLocaleString('en-US')} points lie outside the bounds the header gives ` +
        `(${h.bounds.min.join(', ')} .. ${h.bounds.max.join(', ')}): the header or the points are wrong`,
    ];
  }

  /**
   * Decodes up to `maxPoints` points (default 65536) into new arrays, or into
   * `into` at `into.offset` (points) when given. Returns undefined at the end.
   */
  read(
    maxPoints = DEFAULT_CHUNK,
    fields: LasFields = { positions: true },
    into?: Partial<LasChunk> & { offset: number },
  ): LasChunk | undefined {
    if (this.handle === 0) throw new LasError(this.fileName, 'the reader is closed');
    const wanted = Math.min(maxPoints, this.header.pointCount - this.nextPoint);
    if (wanted <= 0) return undefined;
    let got: number;
    let s: NonNullable<LasReader['scratch']>;
    try {
      s = this.ensureScratch(wanted, fields);
      const n = Math.min(wanted, s.capacity);
      got = this.m._las_read(
        this.handle,
        n,
        s.fields.positions ? s.ptrs.positions : 0,
        s.fields.rgb ? s.ptrs.rgb : 0,
        s.fields.intensity ? s.ptrs.intensity : 0,
        s.fields.classification ? s.ptrs.classification : 0,
        s.fields.xyz ? s.ptrs.xyz : 0,
        s.fields.records ? s.ptrs.records : 0,
      );
      if (got < 0) {
        const reason = this.m.UTF8ToString(ptr(this.m._las_error(this.handle)));
        throw new LasError(this.fileName, reason || 'cannot read the points');
      }
      this.outside = this.m._las_outside(this.handle);
    } catch (e) {
      if (e instanceof LasError) throw e;
      this.abandon();
      throw moduleFailure(this.m, this.fileName, e);
    }
    const start = this.nextPoint;
    this.nextPoint += got;
    // The heap may have grown (and moved) during the call: take a fresh view.
    const heap = this.m.HEAPU8.buffer;
    const chunk: LasChunk = { start, count: got };
    const at = into?.offset ?? 0;
    const copy = <T extends Float32Array | Uint16Array | Uint8Array | Int32Array>(
      make: (b: ArrayBufferLike, o: number, l: number) => T,
      p: number,
      perPoint: number,
      dest: T | undefined,
    ): T => {
      const src = make(heap, p, got * perPoint);
      if (dest) {
        dest.set(src, at * perPoint);
        return dest.subarray(at * perPoint, (at + got) * perPoint) as T;
      }
      return src.slice() as T;
    };
    const f = s.fields;
    if (f.positions) chunk.positions = copy((b, o, l) => new Float32Array(b, o, l), s.ptrs.positions, 3, into?.positions);
    if (f.rgb) chunk.rgb = copy((b, o, l) => new Uint16Array(b, o, l), s.ptrs.rgb, 3, into?.rgb);
    if (f.intensity) chunk.intensity = copy((b, o, l) => new Uint16Array(b, o, l), s.ptrs.intensity, 1, into?.intensity);
    if (f.classification) chunk.classification = copy((b, o, l) => new Uint8Array(b, o, l), s.ptrs.classification, 1, into?.classification);
    if (f.xyz) chunk.xyz = copy((b, o, l) => new Int32Array(b, o, l), s.ptrs.xyz, 3, into?.xyz);
    if (f.records) chunk.records = copy((b, o, l) => new Uint8Array(b, o, l), s.ptrs.records, this.header.pointRecordLength, into?.records);
    return chunk;
  }

  private ensureScratch(n: number, fields: LasFields): NonNullable<LasReader['scratch']> {
    const want: Required<LasFields> = {
      positions: !!fields.positions,
      rgb: !!fields.rgb && this.header.hasRGB,
      intensity: !!fields.intensity,
      classification: !!fields.classification,
      xyz: !!fields.xyz,
      records: !!fields.records,
    };
    const bytesPerPoint: Record<keyof LasFields, number> = {
      positions: 12,
      rgb: 6,
      intensity: 2,
      classification: 1,
      xyz: 12,
      records: this.header.pointRecordLength,
    };
    // Chunks of long records are shortened: n * bytes must fit a 32-bit _malloc, and stay small.
    const perPoint = (Object.keys(want) as (keyof LasFields)[]).reduce((sum, k) => sum + (want[k] ? bytesPerPoint[k] : 0), 0);
    n = Math.max(1, Math.min(n, Math.floor(MAX_CHUNK_BYTES / Math.max(1, perPoint))));
    const s = this.scratch;
    if (s && s.capacity >= n && (Object.keys(want) as (keyof LasFields)[]).every((k) => !want[k] || s.fields[k])) {
      return { ...s, fields: want };
    }
    this.freeScratch();
    const ptrs = { positions: 0, rgb: 0, intensity: 0, classification: 0, xyz: 0, records: 0 };
    for (const k of Object.keys(want) as (keyof LasFields)[]) {
      if (!want[k]) continue;
      // 8-byte aligned by malloc, which typed-array views need.
      ptrs[k] = ptr(this.m._malloc(n * bytesPerPoint[k]));
      if (ptrs[k] === 0) {
        this.scratch = { capacity: n, fields: want, ptrs };
        this.freeScratch();
        throw new LasError(this.fileName, `out of WebAssembly memory for a chunk of ${n} points`);
      }
    }
    this.scratch = { capacity: n, fields: want, ptrs };
    return this.scratch;
  }

  private freeScratch(): void {
    if (!this.scratch) return;
    for (const p of Object.values(this.scratch.ptrs)) if (p) this.m._free(p);
    this.scratch = undefined;
  }

  /** Forgets the file without calling into a module that failed (it is discarded). */
  private abandon(): void {
    this.handle = 0;
    this.scratch = undefined;
  }

  /**
   * Frees the reader, LASzip's state and the file's bytes in the Wasm heap.
   * Never throws: it runs in `finally` blocks, where it must not replace the
   * real outcome; a module that fails here is replaced for the next file.
   */
  close(): void {
    if (this.handle === 0) return;
    const handle = this.handle;
    try {
      this.freeScratch();
    } catch (e) {
      moduleFailure(this.m, this.fileName, e);
      this.abandon();
      return;
    }
    this.abandon();
    closeQuietly(this.m, handle, this.fileName);
  }
}
