// TIFF images and stacks through libtiff (with zlib and libjpeg-turbo)
// compiled to WebAssembly (wasm/tiff).
//
// A multi-page file, or several single- or multi-page files ordered by name,
// becomes one volume laid out [page][y][x][sample] (samples interleaved, in
// the file's sample type). Each file's bytes are copied once into the Wasm
// heap; each page is decoded there and copied straight into its place in the
// volume; the file's Wasm memory is freed before the next file is opened.
// One file's reader is tiff-reader.ts (re-exported here).
import {
  TiffReader,
  TiffError,
  allocateSamples,
  MAX_TIFF_PAGE_BYTES,
  MAX_TIFF_VOLUME_BYTES,
  FIRST_ALLOCATION_BYTES,
  MAX_EXPANSION,
  type SampleType,
  type SampleArray,
  type Vec3,
  type TiffPage,
} from './tiff-reader.ts';
import { formatBytes } from './wasm-module.ts';

export {
  COMPRESSION_NAMES,
  PHOTOMETRIC_NAMES,
  SAMPLE_FORMAT_NAMES,
  MAX_TIFF_PAGE_BYTES,
  MAX_TIFF_VOLUME_BYTES,
  allocateSamples,
  loadTiffWasm,
  sampleType,
  TiffError,
  TiffReader,
} from './tiff-reader.ts';
export type { SampleArray, SampleType, TiffPage, Vec3 } from './tiff-reader.ts';
export interface ImageJInfo {
  /** key=value lines of the ImageJ ImageDescription. */
  fields: Record<string, string>;
  images?: number;
  slices?: number;
  channels?: number;
  frames?: number;
  spacing?: number;
  unit?: string;
}

/** Parses ImageJ's ImageDescription ("ImageJ=1.x\nimages=..\nspacing=.."), or undefined. */
export function parseImageJ(description: string): ImageJInfo | undefined {
  if (!description.startsWith('ImageJ=')) return undefined;
  const fields: Record<string, string> = {};
  for (const line of description.split(/\r?\n/)) {
    const eq = line.indexOf('=');
    if (eq > 0) fields[line.slice(0, eq).trim()] = line.slice(eq + 1).trim();
  }
  const num = (k: string): number | undefined => {
    const v = Number(fields[k]);
    return fields[k] !== undefined && Number.isFinite(v) ? v : undefined;
  };
  const unit = fields.unit?.replace(/\\u00B5/gi, 'µ');
  return {
    fields,
    images: num('images'),
    slices: num('slices'),
    channels: num('channels'),
    frames: num('frames'),
    spacing: num('spacing'),
    unit,
  };
}

export interface TiffVolume {
  /** x, y, z (z = pages). */
  dims: Vec3;
  samplesPerPixel: number;
  dtype: SampleType;
  /** [page][y][x][sample], native byte order. */
  data: SampleArray;
  /** Metadata of every page in the volume, in order. */
  pages: TiffPage[];
  /** The files, in stack order (sorted by name). */
  files: string[];
  /** Pages left out because their shape or type differs from the first (thumbnails, previews). */
  skippedPages: number;
  /** Voxel size from ImageJ metadata (x, y from the resolution, z from `spacing`); undefined if none. */
  spacing?: Vec3;
  unit?: string;
  imagej?: ImageJInfo;
  decodeMs: number;
}

export interface TiffSource {
  name: string;
  /** The file's bytes, or the File itself (streamed into the Wasm heap when its turn comes). */
  bytes: Uint8Array | Blob;
}

export interface LoadTiffOptions {
  /** Called after every page with pages decoded so far and the total. */
  onProgress?: (done: number, total: number) => void;
  /** Yield to the event loop between pages so a page can repaint its progress bar. */
  yieldBetweenPages?: boolean;
  signal?: AbortSignal;
}

/** Natural order: "slice2.tif" before "slice10.tif". */
export function compareNames(a: string, b: string): number {
  return a.localeCompare(b, 'en', { numeric: true, sensitivity: 'base' }) || (a < b ? -1 : a > b ? 1 : 0);
}

function describeShape(p: TiffPage): string {
  return `${p.width}×${p.height}${p.samplesPerPixel > 1 ? `×${p.samplesPerPixel}` : ''} ${p.dtype ?? `${p.bitsPerSample}-bit ${p.sampleFormatName}`}`;
}

/**
 * Loads a multi-page TIFF, or a stack of files (ordered by name), as one volume.
 * Throws TiffError naming the file for unreadable or inconsistent input.
 */
export async function loadTiffStack(sources: TiffSource | TiffSource[], options: LoadTiffOptions = {}): Promise<TiffVolume> {
  const files = (Array.isArray(sources) ? [...sources] : [sources]).sort((a, b) => compareNames(a.name, b.name));
  if (files.length === 0) throw new TiffError('(no file)', 'no TIFF files were given');
  let decodeMs = 0;
  let first: TiffPage | undefined;
  let data: SampleArray | undefined;
  let capacityPages = 0;
  let filled = 0;
  let skipped = 0;
  const pages: TiffPage[] = [];
  let estimatedTotal = 0;
  for (let f = 0; f < files.length; f++) {
    const { name, bytes } = files[f];
    let t0 = performance.now();
    const reader = await TiffReader.open(bytes, name);
    try {
      if (!first) {
        // The first full-resolution page sets the stack's shape (thumbnails come first in some files).
        for (let i = 0; i < reader.pageCount && !first; i++) if (!reader.page(i).reducedResolution) first = reader.page(i);
        first ??= reader.page(0);
        if (!first.dtype) throw new TiffError(name, unsupportedSamples(first));
        if (first.width * first.height === 0) throw new TiffError(name, 'the image is empty (0 pixels)');
        const bytes = pageBytes(first);
        if (bytes > MAX_TIFF_PAGE_BYTES) {
          throw new TiffError(
            name,
            `the pages are ${describeShape(first)} (${formatBytes(bytes)} each), more than the largest page this reader decodes (${formatBytes(MAX_TIFF_PAGE_BYTES)})`,
          );
        }
      }
      const perPage = first.width * first.height * first.samplesPerPixel;
      let used = 0;
      // One forward walk: each page's directory is read once, then its data decoded.
      for (let i = 0; i < reader.pageCount; i++) {
        const p = reader.page(i);
        if (p.reducedResolution || !sameShape(p, first)) {
          skipped++;
          continue;
        }
        // A directory's size claims are checked against the data it stores before anything is allocated.
        const expansion = p.compression === 1 ? 1 : MAX_EXPANSION;
        if (pageBytes(p) > p.dataBytes * expansion) {
          throw new TiffError(
            name,
            p.compression === 1
              ? `truncated or corrupt file: page ${i} is ${describeShape(p)} (${formatBytes(pageBytes(p))}) but its strips hold ${formatBytes(p.dataBytes)}`
              : `corrupt file: page ${i} claims ${describeShape(p)} (${formatBytes(pageBytes(p))}) from ${formatBytes(p.dataBytes)} of compressed data`,
          );
        }
        if (!data || filled + 1 > capacityPages) {
          // The stack's size is known only file by file: assume the rest are like this one.
          estimatedTotal = filled + (reader.pageCount - i) + reader.pageCount * (files.length - f - 1);
          // Directories are not trusted: allocate no more pages than the files' bytes can expand to.
          const bytesLeft = files.slice(f).reduce((sum, s) => sum + (s.bytes instanceof Uint8Array ? s.bytes.byteLength : s.bytes.size), 0);
          const plausible = filled + Math.floor((bytesLeft * (p.compression === 1 ? 1 : MAX_EXPANSION)) / pageBytes(first)) + 1;
          const maxPages = Math.floor(MAX_TIFF_VOLUME_BYTES / pageBytes(first));
          if (filled + 1 > maxPages) {
            throw new TiffError(
              name,
              `the stack has at least ${(filled + 1).toLocaleString('en-US')} pages of ${describeShape(first)} (${formatBytes((filled + 1) * pageBytes(first))}), ` +
                `more than the largest volume this reader loads (${formatBytes(MAX_TIFF_VOLUME_BYTES)})`,
            );
          }
          // Before any page has decoded, trust the directories for at most 64 MiB; after, grow to
          // the estimate (at least doubling, so a stack of many files is copied O(log n) times).
          const want =
            filled === 0
              ? Math.min(estimatedTotal, Math.floor(FIRST_ALLOCATION_BYTES / pageBytes(first)))
              : Math.max(estimatedTotal, 2 * capacityPages);
          capacityPages = Math.min(maxPages, plausible, Math.max(filled + 1, want));
          const grown = allocateSamples(first.dtype!, perPage * capacityPages);
          if (data) grown.set(data.subarray(0, filled * perPage) as never);
          data = grown;
        }
        reader.readPage(i, data, filled * perPage);
        pages.push(p);
        filled++;
        used++;
        decodeMs += performance.now() - t0;
        options.onProgress?.(filled, Math.max(estimatedTotal, filled));
        if (options.yieldBetweenPages) await new Promise((r) => setTimeout(r, 0));
        if (options.signal?.aborted) throw new TiffError(name, 'loading was cancelled');
        t0 = performance.now();
      }
      if (used === 0) {
        throw new TiffError(name, `its pages (${describeShape(reader.page(0))}) do not match the stack (${describeShape(first)})`);
      }
      decodeMs += performance.now() - t0;
    } finally {
      reader.close();
    }
  }
  const perPage = first!.width * first!.height * first!.samplesPerPixel;
  const volumeData = filled === capacityPages ? data! : (data!.slice(0, filled * perPage) as SampleArray);
  const imagej = parseImageJ(pages[0].description);
  let spacing: Vec3 | undefined;
  let unit: string | undefined;
  if (imagej) {
    const sx = first!.xResolution > 0 ? 1 / first!.xResolution : 1;
    const sy = first!.yResolution > 0 ? 1 / first!.yResolution : sx;
    spacing = [sx, sy, imagej.spacing ?? 1];
    unit = imagej.unit;
  }
  return {
    dims: [first!.width, first!.height, filled],
    samplesPerPixel: first!.samplesPerPixel,
    dtype: first!.dtype!,
    data: volumeData,
    pages,
    files: files.map((f) => f.name),
    skippedPages: skipped,
    spacing,
    unit,
    imagej,
    decodeMs,
  };
}

/** The same wording as the C API's checks (wasm/tiff/tiff_api.c). */
function unsupportedSamples(p: TiffPage): string {
  if (p.sampleFormat === 3) return `unsupported ${p.bitsPerSample}-bit floating-point samples (32 and 64 are supported)`;
  if (p.sampleFormat !== 1 && p.sampleFormat !== 2) {
    return `unsupported sample format ${p.sampleFormat} (unsigned, signed integer and IEEE float are supported)`;
  }
  return `unsupported sample size: ${p.bitsPerSample} bits per sample (8, 16 and 32-bit integers are supported)`;
}

/** Decoded bytes of one page (samples of 8 to 64 bits). */
function pageBytes(p: TiffPage): number {
  return p.width * p.height * p.samplesPerPixel * Math.max(1, p.bitsPerSample / 8);
}

function sameShape(p: TiffPage, q: TiffPage): boolean {
  return (
    p.width === q.width && p.height === q.height && p.samplesPerPixel === q.samplesPerPixel && p.dtype === q.dtype && p.dtype !== undefined
  );
}

/** min, max and mean over all samples (float64 accumulation). */
export function sampleStats(data: SampleArray): { min: number; max: number; mean: number } {
  let min = Infinity;
  let max = -Infinity;
  // Sum in blocks: keeps the float64 rounding error small for huge volumes.
  let total = 0;
  const block = 1 << 16;
  for (let start = 0; start < data.length; start += block) {
    let s = 0;
    const end = Math.min(data.length, start + block);
    for (let i = start; i < end; i++) {
      const v = data[i];
      if (v < min) min = v;
      if (v > max) max = v;
      s += v;
    }
    total += s;
  }
  return { min, max, mean: data.length > 0 ? total / data.length : NaN };
}
