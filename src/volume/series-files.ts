// The files of a time series (one 3-D volume per file, all of one shape and
// type: raw, NRRD or TIFF stacks) checked against each other and read z
// planes at a time. Checking reads what each file says about itself (a raw
// file's length and the shape in its name, a NRRD header, a TIFF's page
// directories) and refuses the set by the first file that does not fit,
// naming it, before anything is read of the data. Reading then takes what
// is asked for: a raw file's planes are one byte range (File.slice), a raw
// NRRD's too (after its header); a TIFF or a gzip NRRD time point is decoded
// whole on first use and kept in a small cache (the two most recent).
// Files are hostile: every size is checked against the file's length and
// sane limits before anything is allocated.
import { DTYPE_BYTES, type DType } from '../core/dtype.ts';
import { surfaceDimsProblem } from '../core/limits.ts';
import { type Dims, parseVolumeName } from '../core/naming.ts';
import type { TiffPage, TiffReader } from '../loaders/tiff.ts';
import { NrrdError, type NrrdLayout, nrrdLayout, parseNrrd, parseNrrdHeader } from './nrrd.ts';
import type { SeriesFileKind } from './series-names.ts';

/** Value types of a series (TIFF's 32-bit integers as they are: the store reads them as float32). */
export type SeriesDType = DType | 'uint32' | 'int32';

export const SERIES_DTYPE_BYTES: Record<SeriesDType, number> = { ...DTYPE_BYTES, uint32: 4, int32: 4 };

/** At most this many files in a series. */
export const MAX_SERIES_FILES = 100_000;
/** A time point decoded whole (TIFF, gzip NRRD) holds at most this many bytes. */
export const MAX_DECODED_BYTES = 2 ** 31;
/** Decoded time points kept: at most this many, and within this many bytes together (at least one). */
const CACHE_ENTRIES = 2;
const CACHE_BYTES = 2 ** 30;

export class SeriesError extends Error {
  constructor(message: string) {
    super(message);
    this.name = 'SeriesError';
  }
}

/** A checked series: every file one volume of `dims` and `dtype`. */
export interface SeriesFiles {
  kind: SeriesFileKind;
  /** The files' names, in time order. */
  names: string[];
  dims: Dims;
  dtype: SeriesDType;
  /** World size of a voxel (the first file's NRRD spacing or ImageJ calibration), when it gives one. */
  spacing?: [number, number, number];
  /** Planes z0 .. z0 + nz - 1 of time point t: little endian, x fastest, exactly nz planes. */
  readPlanes(t: number, z0: number, nz: number): Promise<Uint8Array>;
}

export const shapeText = (dims: Dims, dtype?: string) => `${dims.join('×')}${dtype ? ` ${dtype}` : ''}`;
const count = (n: number) => n.toLocaleString('en-US');
const sameDims = (a: Dims, b: Dims) => a[0] === b[0] && a[1] === b[1] && a[2] === b[2];

/** Bytes of one time point. */
export function seriesVolumeBytes(dims: Dims, dtype: SeriesDType): number {
  return dims[0] * dims[1] * dims[2] * SERIES_DTYPE_BYTES[dtype];
}

function checkCommon(files: readonly File[], dims: Dims): void {
  if (files.length < 1) throw new SeriesError('no files were given');
  if (files.length > MAX_SERIES_FILES)
    throw new SeriesError(`${count(files.length)} files: more than the ${count(MAX_SERIES_FILES)} time points a series may have`);
  const wide = surfaceDimsProblem(dims);
  if (wide) throw new SeriesError(`${files[0].name}: ${wide}`);
}

/**
 * Checks a series of raw files against the shape and type given (from the
 * first file's name or the form): each file's name, when it carries a shape,
 * must carry this one, and each file's length must be what it takes.
 */
export function rawSeries(files: readonly File[], dims: Dims, dtype: DType): SeriesFiles {
  if (dims.some((n) => !Number.isSafeInteger(n) || n < 1))
    throw new SeriesError(`${files[0]?.name ?? '(no file)'}: the shape ${shapeText(dims)} is impossible`);
  checkCommon(files, dims);
  const need = seriesVolumeBytes(dims, dtype);
  for (const f of files) {
    const named = parseVolumeName(f.name);
    if (named.dims && (!sameDims(named.dims, dims) || (named.dtype && named.dtype !== dtype)))
      throw new SeriesError(
        `${f.name}: the name says ${shapeText(named.dims, named.dtype)}, the series' first file ${files[0].name} is ${shapeText(dims, dtype)}`,
      );
    if (f.size !== need)
      throw new SeriesError(`${f.name}: ${count(f.size)} bytes; the series' shape ${shapeText(dims, dtype)} needs ${count(need)}`);
  }
  const plane = dims[0] * dims[1] * SERIES_DTYPE_BYTES[dtype];
  return {
    kind: 'raw',
    names: files.map((f) => f.name),
    dims,
    dtype,
    readPlanes: (t, z0, nz) => readRange(files[t], z0 * plane, nz * plane),
  };
}

/** `length` bytes of `file` from `offset`, or an error naming the file (it changed since it was checked). */
async function readRange(file: File, offset: number, length: number): Promise<Uint8Array> {
  const bytes = new Uint8Array(await file.slice(offset, offset + length).arrayBuffer());
  if (bytes.byteLength !== length)
    throw new SeriesError(
      `${file.name}: ${count(bytes.byteLength)} bytes at ${count(offset)} where ${count(length)} were expected (the file changed?)`,
    );
  return bytes;
}

/** Swaps the bytes of each `width`-byte value in place (big-endian samples to little). */
function swapBytes(bytes: Uint8Array, width: number): Uint8Array {
  if (width > 1) for (let i = 0; i < bytes.length; i += width) bytes.subarray(i, i + width).reverse();
  return bytes;
}

/**
 * Checks a series of NRRD files (attached data, raw or gzip): every header
 * read (its first 64 KiB), every shape and type the first file's, raw data
 * within the file's length.
 */
export async function nrrdSeries(files: readonly File[]): Promise<SeriesFiles> {
  const heads: { layout: NrrdLayout; dataOffset: number }[] = [];
  for (const f of files) {
    let head: { layout: NrrdLayout; dataOffset: number };
    try {
      const { fields, dataOffset } = parseNrrdHeader(new Uint8Array(await f.slice(0, 1 << 16).arrayBuffer()));
      head = { layout: nrrdLayout(fields), dataOffset };
    } catch (e) {
      if (e instanceof NrrdError) throw new SeriesError(`${f.name}: ${e.message}`);
      throw e;
    }
    const first = heads[0]?.layout ?? head.layout;
    if (!sameDims(head.layout.dims, first.dims) || head.layout.dtype !== first.dtype)
      throw new SeriesError(
        `${f.name}: ${shapeText(head.layout.dims, head.layout.dtype)}, the series' first file ${files[0].name} is ${shapeText(first.dims, first.dtype)}`,
      );
    if (!head.layout.gzip && head.dataOffset + head.layout.need > f.size)
      throw new SeriesError(
        `${f.name}: truncated: ${shapeText(head.layout.dims, head.layout.dtype)} needs ${count(head.layout.need)} bytes of data, the file has ${count(Math.max(0, f.size - head.dataOffset))}`,
      );
    heads.push(head);
  }
  const { dims, dtype, spacing } = heads[0].layout;
  checkCommon(files, dims);
  const width = DTYPE_BYTES[dtype];
  const plane = dims[0] * dims[1] * width;
  const whole = new DecodedCache(seriesVolumeBytes(dims, dtype), async (t) => {
    try {
      return (await parseNrrd(new Uint8Array(await files[t].arrayBuffer()))).data;
    } catch (e) {
      if (e instanceof NrrdError) throw new SeriesError(`${files[t].name}: ${e.message}`);
      throw e;
    }
  });
  return {
    kind: 'nrrd',
    names: files.map((f) => f.name),
    dims,
    dtype,
    ...(spacing ? { spacing } : {}),
    readPlanes: async (t, z0, nz) => {
      const h = heads[t];
      if (h.layout.gzip) return (await whole.get(t)).slice(z0 * plane, (z0 + nz) * plane);
      const bytes = await readRange(files[t], h.dataOffset + z0 * plane, nz * plane);
      return h.layout.bigEndian ? swapBytes(bytes, width) : bytes;
    },
  };
}

/** What one TIFF file holds as a volume: its full-resolution pages of the first one's shape, as loadTiffStack takes them. */
async function tiffShape(file: File): Promise<{ dims: Dims; dtype: SeriesDType; first: TiffPage }> {
  const { TiffReader: Reader, TiffError } = await import('../loaders/tiff.ts');
  let reader: TiffReader;
  try {
    reader = await Reader.open(file, file.name);
  } catch (e) {
    if (e instanceof TiffError) throw new SeriesError(e.message);
    throw e;
  }
  try {
    let first: TiffPage | undefined;
    let pages = 0;
    for (let i = 0; i < reader.pageCount; i++) {
      const p = reader.page(i);
      if (p.reducedResolution) continue;
      const f0: TiffPage = first ?? p;
      first = f0;
      if (p.width === f0.width && p.height === f0.height && p.samplesPerPixel === f0.samplesPerPixel && p.dtype === f0.dtype) pages++;
    }
    if (!first) throw new SeriesError(`${file.name}: no full-resolution page`);
    if (!first.dtype) throw new SeriesError(`${file.name}: ${first.bitsPerSample}-bit ${first.sampleFormatName} samples cannot be decoded`);
    if (first.samplesPerPixel !== 1)
      throw new SeriesError(
        `${file.name}: ${first.samplesPerPixel} samples per pixel (colour); an isosurface needs one value per voxel (save a single channel)`,
      );
    return { dims: [first.width, first.height, pages], dtype: first.dtype, first };
  } catch (e) {
    if (e instanceof TiffError) throw new SeriesError(e.message);
    throw e;
  } finally {
    reader.close();
  }
}

/** The number of full-resolution pages of one TIFF file (1: a slice of a z stack; more: a 3-D stack). */
export async function tiffPageCount(file: File): Promise<number> {
  return (await tiffShape(file)).dims[2];
}

/**
 * Checks a series of 3-D TIFF stacks (one multi-page file per time point):
 * every file's directories read (libtiff), every shape and type the first
 * file's. A time point is decoded whole when first asked for.
 */
export async function tiffSeries(files: readonly File[]): Promise<SeriesFiles> {
  let dims: Dims | undefined;
  let dtype: SeriesDType | undefined;
  let first: TiffPage | undefined;
  for (const f of files) {
    const s = await tiffShape(f);
    if (!dims) {
      ({ dims, dtype, first } = s);
      checkCommon(files, dims);
      if (seriesVolumeBytes(dims, dtype!) > MAX_DECODED_BYTES)
        throw new SeriesError(`${f.name}: ${shapeText(dims, dtype)} is more than a time point this page decodes whole (2 GiB)`);
    } else if (!sameDims(s.dims, dims) || s.dtype !== dtype) {
      throw new SeriesError(
        `${f.name}: ${shapeText(s.dims, s.dtype === dtype ? undefined : s.dtype)}, the series' first file ${files[0].name} is ${shapeText(dims, s.dtype === dtype ? undefined : dtype)}`,
      );
    }
  }
  const { loadTiffStack, parseImageJ, TiffError } = await import('../loaders/tiff.ts');
  const bytes = seriesVolumeBytes(dims!, dtype!);
  const whole = new DecodedCache(bytes, async (t) => {
    const f = files[t];
    try {
      const v = await loadTiffStack({ name: f.name, bytes: f });
      if (!sameDims(v.dims, dims!) || v.dtype !== dtype || v.data.byteLength !== bytes)
        throw new SeriesError(`${f.name}: decoded as ${shapeText(v.dims, v.dtype)}, not ${shapeText(dims!, dtype)} (the file changed?)`);
      return new Uint8Array(v.data.buffer, v.data.byteOffset, v.data.byteLength);
    } catch (e) {
      if (e instanceof TiffError) throw new SeriesError(e.message);
      throw e;
    }
  });
  const plane = dims![0] * dims![1] * SERIES_DTYPE_BYTES[dtype!];
  // ImageJ calibration of the first file, as a single stack takes it
  const imagej = parseImageJ(first!.description);
  const spacing: [number, number, number] | undefined = imagej
    ? (() => {
        const sx = first!.xResolution > 0 ? 1 / first!.xResolution : 1;
        const sy = first!.yResolution > 0 ? 1 / first!.yResolution : sx;
        return [sx, sy, imagej.spacing ?? 1];
      })()
    : undefined;
  return {
    kind: 'tiff',
    names: files.map((f) => f.name),
    dims: dims!,
    dtype: dtype!,
    ...(spacing ? { spacing } : {}),
    readPlanes: async (t, z0, nz) => (await whole.get(t)).slice(z0 * plane, (z0 + nz) * plane),
  };
}

/**
 * Time points decoded whole, the most recent kept (CACHE_ENTRIES, within
 * CACHE_BYTES, at least one); concurrent requests of one time point share
 * its decoding, decodings run one at a time; a failed decoding is not kept.
 */
export class DecodedCache {
  readonly #entries = new Map<number, Promise<Uint8Array>>();
  readonly #max: number;
  /** The decoding under way (or done): the next starts after it. */
  #queue: Promise<void> = Promise.resolve();
  /** Decodings started (tests). */
  decoded = 0;

  constructor(
    bytesEach: number,
    private readonly decode: (t: number) => Promise<Uint8Array>,
  ) {
    this.#max = Math.max(1, Math.min(CACHE_ENTRIES, Math.floor(CACHE_BYTES / Math.max(1, bytesEach))));
  }

  get(t: number): Promise<Uint8Array> {
    let p = this.#entries.get(t);
    if (p) {
      // most recent last
      this.#entries.delete(t);
      this.#entries.set(t, p);
      return p;
    }
    this.decoded++;
    // one decoding at a time: the TIFF decoder is one Wasm instance (two time points decoded at once, the
    // one shown and the next fetched ahead, mixed their planes), and two time points whole are memory enough
    p = this.#queue.then(() => this.decode(t));
    this.#queue = p.then(
      () => undefined,
      () => undefined,
    );
    this.#entries.set(t, p);
    p.catch(() => {
      if (this.#entries.get(t) === p) this.#entries.delete(t);
    });
    while (this.#entries.size > this.#max) this.#entries.delete(this.#entries.keys().next().value!);
    return p;
  }
}
