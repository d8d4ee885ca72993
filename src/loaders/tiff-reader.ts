// One TIFF file through libtiff (with zlib and libjpeg-turbo) compiled to
// WebAssembly (wasm/tiff): the module, its page descriptions and the page
// decoder (TiffReader), with every size checked before the Wasm heap sees
// it. Stacks of pages and files: tiff.ts.
import createTiffModule, { type TiffWasm } from '../../wasm/dist/tiff.js';
import { copyIntoHeap, describeWasmFailure, formatBytes, instantiateWasm, ptr, streamIntoHeap, WasmSlot } from './wasm-module.ts';

export type SampleType = 'uint8' | 'int8' | 'uint16' | 'int16' | 'uint32' | 'int32' | 'float32' | 'float64';
export type SampleArray = Uint8Array | Int8Array | Uint16Array | Int16Array | Uint32Array | Int32Array | Float32Array | Float64Array;
export type Vec3 = [number, number, number];

export const COMPRESSION_NAMES: Record<number, string> = {
  1: 'NONE',
  2: 'CCITTRLE',
  3: 'CCITT_T4',
  4: 'CCITT_T6',
  5: 'LZW',
  6: 'OJPEG',
  7: 'JPEG',
  8: 'ADOBE_DEFLATE',
  32771: 'CCITTRLEW',
  32773: 'PACKBITS',
  32809: 'THUNDERSCAN',
  32946: 'DEFLATE',
  34676: 'SGILOG',
  34677: 'SGILOG24',
  34712: 'JPEG2000',
  34887: 'LERC',
  34925: 'LZMA',
  50000: 'ZSTD',
  50001: 'WEBP',
  50002: 'JPEGXL',
};
export const SAMPLE_FORMAT_NAMES: Record<number, string> = {
  1: 'UINT',
  2: 'INT',
  3: 'IEEEFP',
  4: 'VOID',
  5: 'COMPLEXINT',
  6: 'COMPLEXIEEEFP',
};
export const PHOTOMETRIC_NAMES: Record<number, string> = {
  0: 'MINISWHITE',
  1: 'MINISBLACK',
  2: 'RGB',
  3: 'PALETTE',
  4: 'MASK',
  5: 'SEPARATED',
  6: 'YCBCR',
  8: 'CIELAB',
  32844: 'LOGL',
  32845: 'LOGLUV',
};

export interface TiffPage {
  /** Page (IFD) index in its file. */
  index: number;
  fileName: string;
  width: number;
  height: number;
  bitsPerSample: number;
  samplesPerPixel: number;
  sampleFormat: number;
  sampleFormatName: string;
  compression: number;
  compressionName: string;
  photometric: number;
  photometricName: string;
  /** 1 chunky, 2 planar (separate). */
  planarConfig: number;
  tiled: boolean;
  tileWidth: number;
  tileHeight: number;
  rowsPerStrip: number;
  xResolution: number;
  yResolution: number;
  /** 1 none, 2 inch, 3 centimetre. */
  resolutionUnit: number;
  /** NewSubfileType bit 0: a thumbnail / pyramid level, not part of the stack. */
  reducedResolution: boolean;
  bigEndian: boolean;
  bigTiff: boolean;
  description: string;
  /** The decoded sample type, or undefined when this build cannot decode the page. */
  dtype?: SampleType;
  /** Bytes of (possibly compressed) strip or tile data the page stores in the file. */
  dataBytes: number;
}

/** A file that is not a readable TIFF (or stack); the message names the file. */
export class TiffError extends Error {
  constructor(
    readonly fileName: string,
    readonly reason: string,
  ) {
    super(`${fileName}: ${reason}`);
    this.name = 'TiffError';
  }
}

const slot = new WasmSlot(() => instantiateWasm(createTiffModule, new URL('../../wasm/dist/tiff.wasm', import.meta.url), 'TIFF'));

/** The libtiff module (instantiated once per page or process; replaced after it failed on a file). */
export function loadTiffWasm(): Promise<TiffWasm> {
  return slot.get();
}

/** A failure inside the module (trap, glue error): the module is replaced, the file rejected. */
function moduleFailure(m: TiffWasm, fileName: string, e: unknown): TiffError {
  if (e instanceof TiffError) return e;
  const what = describeWasmFailure(e);
  slot.discard(m, `${fileName}: ${what}`);
  return new TiffError(fileName, `the file is corrupt in a way the TIFF decoder could not handle (${what})`);
}

const PAGE_FIELDS = 19;
/** The largest decoded page, as in wasm/tiff/tiff_api.c (MAX_PAGE_BYTES). */
export const MAX_TIFF_PAGE_BYTES = 2 ** 30;
/** The largest volume loadTiffStack builds (one typed array). */
export const MAX_TIFF_VOLUME_BYTES = 2 ** 31;
/** What loadTiffStack allocates before the first page has decoded. */
export const FIRST_ALLOCATION_BYTES = 64 * 2 ** 20;
/** No codec in the build expands data more than this (tiff_api.c, MAX_EXPANSION). */
export const MAX_EXPANSION = 4096;

export function sampleType(bits: number, format: number): SampleType | undefined {
  if (format === 3) return bits === 32 ? 'float32' : bits === 64 ? 'float64' : undefined;
  if (format !== 1 && format !== 2) return undefined;
  const signed = format === 2;
  if (bits === 8) return signed ? 'int8' : 'uint8';
  if (bits === 16) return signed ? 'int16' : 'uint16';
  if (bits === 32) return signed ? 'int32' : 'uint32';
  return undefined;
}

const ARRAY_TYPES = {
  uint8: Uint8Array,
  int8: Int8Array,
  uint16: Uint16Array,
  int16: Int16Array,
  uint32: Uint32Array,
  int32: Int32Array,
  float32: Float32Array,
  float64: Float64Array,
} as const;

export function allocateSamples(dtype: SampleType, length: number): SampleArray {
  return new ARRAY_TYPES[dtype](length);
}

function closeQuietly(m: TiffWasm, handle: number, fileName: string): void {
  try {
    m._tiff_close(handle);
  } catch (e) {
    moduleFailure(m, fileName, e);
  }
}

/** An open TIFF file in the Wasm heap. Call close() when done. */
export class TiffReader {
  private handle: number;
  private readonly infos: (TiffPage | undefined)[];
  private infoPtr = 0;

  private constructor(
    private readonly m: TiffWasm,
    handle: number,
    readonly fileName: string,
    /** Top-level directories (pages) in the file. */
    readonly pageCount: number,
  ) {
    this.handle = handle;
    this.infos = new Array<TiffPage | undefined>(pageCount);
  }

  /**
   * Opens `bytes`, or a Blob/File streamed straight into the heap (the file's
   * only copy). Throws TiffError for bad files.
   */
  static async open(bytes: Uint8Array | Blob, fileName: string): Promise<TiffReader> {
    const m = await loadTiffWasm();
    const size = bytes instanceof Uint8Array ? bytes.byteLength : bytes.size;
    if (size > 0xffffffff) throw new TiffError(fileName, 'files over 4 GiB do not fit in WebAssembly memory');
    let data: number;
    try {
      data = bytes instanceof Uint8Array ? copyIntoHeap(m, bytes, fileName) : await streamIntoHeap(m, bytes, fileName);
    } catch (e) {
      throw new TiffError(fileName, (e as Error).message.replace(`${fileName}: `, ''));
    }
    // tiff_open owns `data` from here on, also when it fails.
    let handle = 0;
    let pageCount = 0;
    try {
      handle = ptr(m._tiff_open(data, size));
      if (handle === 0) throw new TiffError(fileName, 'out of WebAssembly memory');
      const error = m.UTF8ToString(ptr(m._tiff_error(handle)));
      if (error) throw new TiffError(fileName, error);
      pageCount = m._tiff_page_count(handle);
    } catch (e) {
      if (handle !== 0 && e instanceof TiffError) closeQuietly(m, handle, fileName);
      throw moduleFailure(m, fileName, e);
    }
    const reader = new TiffReader(m, handle, fileName, pageCount);
    try {
      reader.page(0);
    } catch (e) {
      reader.close();
      throw e;
    }
    return reader;
  }

  /** Runs calls into the module; a failure there discards the module and rejects the file. */
  private guard<R>(f: () => R): R {
    try {
      return f();
    } catch (e) {
      if (e instanceof TiffError) throw e;
      this.handle = 0;
      this.infoPtr = 0;
      throw moduleFailure(this.m, this.fileName, e);
    }
  }

  /**
   * Facts of page `index`, read from its directory on first use. Reading
   * pages in order walks the directory chain once (libtiff steps to the next
   * directory; going back restarts from the first).
   */
  page(index: number): TiffPage {
    const known = this.infos[index];
    if (known) return known;
    return this.guard(() => this.readPageInfo(index));
  }

  private readPageInfo(index: number): TiffPage {
    if (this.handle === 0) throw new TiffError(this.fileName, 'the reader is closed');
    if (!(index >= 0 && index < this.pageCount))
      throw new TiffError(this.fileName, `page ${index} does not exist (the file has ${this.pageCount})`);
    const m = this.m;
    if (this.infoPtr === 0) this.infoPtr = ptr(m._malloc(PAGE_FIELDS * 8));
    if (this.infoPtr === 0) throw new TiffError(this.fileName, 'out of WebAssembly memory');
    if (m._tiff_page_info(this.handle, index, this.infoPtr) !== 0) {
      throw new TiffError(
        this.fileName,
        `page ${index}: ${m.UTF8ToString(ptr(m._tiff_error(this.handle))) || 'cannot read its directory'}`,
      );
    }
    const v = new Float64Array(m.HEAPU8.buffer, this.infoPtr, PAGE_FIELDS).slice();
    const page: TiffPage = {
      index,
      fileName: this.fileName,
      width: v[0],
      height: v[1],
      bitsPerSample: v[2],
      samplesPerPixel: v[3],
      sampleFormat: v[4],
      sampleFormatName: SAMPLE_FORMAT_NAMES[v[4]] ?? String(v[4]),
      compression: v[5],
      compressionName: COMPRESSION_NAMES[v[5]] ?? String(v[5]),
      photometric: v[6],
      photometricName: PHOTOMETRIC_NAMES[v[6]] ?? String(v[6]),
      planarConfig: v[7],
      tiled: v[8] === 1,
      tileWidth: v[9],
      tileHeight: v[10],
      rowsPerStrip: v[11],
      xResolution: v[12],
      yResolution: v[13],
      resolutionUnit: v[14],
      reducedResolution: (v[15] & 1) === 1,
      bigEndian: v[16] === 1,
      bigTiff: v[17] === 1,
      description: m.UTF8ToString(ptr(m._tiff_page_description(this.handle, index))),
      dtype: sampleType(v[2], v[4]),
      dataBytes: v[18],
    };
    this.infos[index] = page;
    return page;
  }

  /** Facts of every page (reads all directories). */
  get pages(): TiffPage[] {
    return Array.from({ length: this.pageCount }, (_, i) => this.page(i));
  }

  get closed(): boolean {
    return this.handle === 0;
  }

  /**
   * Decodes page `index` ([y][x][sample]) into a new array, or into `into`
   * starting at element `offset`. Throws TiffError when the page cannot be decoded.
   */
  readPage(index: number, into?: SampleArray, offset = 0): SampleArray {
    if (this.handle === 0) throw new TiffError(this.fileName, 'the reader is closed');
    const page = this.page(index);
    return this.guard(() => this.decodePage(page, index, into, offset));
  }

  private decodePage(page: TiffPage, index: number, into: SampleArray | undefined, offset: number): SampleArray {
    const m = this.m;
    const bytes = m._tiff_page_bytes(this.handle, index);
    if (!(bytes > 0) || !page.dtype) {
      const reason = m.UTF8ToString(ptr(m._tiff_error(this.handle)));
      throw new TiffError(this.fileName, `page ${index}: ${reason || 'cannot be decoded'}`);
    }
    // The C API refuses larger pages; never hand _malloc (32-bit sizes) more than it can give.
    if (bytes > MAX_TIFF_PAGE_BYTES)
      throw new TiffError(
        this.fileName,
        `page ${index} is ${formatBytes(bytes)}, more than the largest page this reader decodes (${formatBytes(MAX_TIFF_PAGE_BYTES)})`,
      );
    const out = ptr(m._malloc(bytes));
    if (out === 0) throw new TiffError(this.fileName, `out of WebAssembly memory for a ${formatBytes(bytes)} page`);
    try {
      if (m._tiff_read_page(this.handle, index, out, bytes) !== 0) {
        const reason = m.UTF8ToString(ptr(m._tiff_error(this.handle)));
        throw new TiffError(this.fileName, `page ${index}: ${reason || 'cannot be decoded'}`);
      }
      const dest = into ?? allocateSamples(page.dtype, bytes / (page.bitsPerSample / 8));
      const bpe = dest.BYTES_PER_ELEMENT;
      if ((offset + bytes / bpe) * bpe > dest.byteLength)
        throw new TiffError(this.fileName, `page ${index} does not fit the destination array`);
      // The heap may have grown during the call: take a fresh view.
      new Uint8Array(dest.buffer, dest.byteOffset + offset * bpe, bytes).set(m.HEAPU8.subarray(out, out + bytes));
      return dest;
    } finally {
      m._free(out);
    }
  }

  /**
   * Frees libtiff's state and the file's bytes in the Wasm heap. Never throws
   * (it runs in `finally` blocks, where it must not replace the real outcome).
   */
  close(): void {
    if (this.handle === 0) return;
    const { handle, infoPtr } = this;
    this.handle = 0;
    this.infoPtr = 0;
    try {
      if (infoPtr) this.m._free(infoPtr);
    } catch (e) {
      moduleFailure(this.m, this.fileName, e);
      return;
    }
    closeQuietly(this.m, handle, this.fileName);
  }
}
