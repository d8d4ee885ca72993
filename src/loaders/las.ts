// LAS/LAZ point clouds through LASzip compiled to WebAssembly (wasm/las).
//
// The file's bytes are copied once into the Wasm heap and decoded there in
// chunks; each chunk is copied out of the heap straight into its place in the
// caller's arrays. Positions are float32 relative to the centre of the
// header's bounds (`header.centre`, float64), so UTM-sized coordinates keep
// their precision. Every reader frees its Wasm memory on close(), also after
// errors.
// One file's reader is las-reader.ts (re-exported here).
import { LasReader, LasError, MAX_CLOUD_POINTS, type Vec3, type LasHeader, type LasChunk } from './las-reader.ts';
import { formatBytes } from './wasm-module.ts';

export { LasError, LasReader, loadLasWasm, MAX_CLOUD_POINTS } from './las-reader.ts';
export type { LasChunk, LasFields, LasHeader, Vec3 } from './las-reader.ts';

export interface PointCloud {
  fileName: string;
  header: LasHeader;
  count: number;
  /** float32 x, y, z relative to `header.centre`. */
  positions: Float32Array;
  /** uint16 r, g, b when the format has RGB. */
  rgb?: Uint16Array;
  intensity: Uint16Array;
  classification: Uint8Array;
  /** Bounds of `positions` (relative to the centre), from the points. */
  localBounds: { min: Vec3; max: Vec3 };
  /** Milliseconds spent decoding (open + all chunks, without waits for the event loop). */
  decodeMs: number;
  /** Problems that did not stop the file from loading (points outside the header's bounds, ...). */
  warnings: string[];
}

export interface LoadPointCloudOptions {
  /** Points per chunk (default 262144). */
  chunkSize?: number;
  /** Called after every chunk with points read so far and the total. */
  onProgress?: (done: number, total: number) => void;
  /** Called with every decoded chunk (views into the result arrays), e.g. to upload it. */
  onChunk?: (chunk: LasChunk, header: LasHeader) => void;
  /** Yield to the event loop between chunks so a page can repaint its progress bar. */
  yieldBetweenChunks?: boolean;
  signal?: AbortSignal;
}

/** Reads a whole LAS/LAZ file into typed arrays, in chunks, with progress. */
export async function loadPointCloud(bytes: Uint8Array, fileName: string, options: LoadPointCloudOptions = {}): Promise<PointCloud> {
  let decodeMs = 0;
  let t0 = performance.now();
  const reader = await LasReader.open(bytes, fileName);
  try {
    const { header } = reader;
    const n = header.pointCount;
    if (n > MAX_CLOUD_POINTS) {
      throw new LasError(
        fileName,
        `the file has ${n.toLocaleString('en-US')} points (${formatBytes(n * 21)} in memory), more than this reader loads at once (${MAX_CLOUD_POINTS.toLocaleString('en-US')})`,
      );
    }
    const out = {
      positions: new Float32Array(n * 3),
      rgb: header.hasRGB ? new Uint16Array(n * 3) : undefined,
      intensity: new Uint16Array(n),
      classification: new Uint8Array(n),
    };
    const min: Vec3 = [Infinity, Infinity, Infinity];
    const max: Vec3 = [-Infinity, -Infinity, -Infinity];
    const chunkSize = options.chunkSize ?? 1 << 18;
    const fields = { positions: true, rgb: header.hasRGB, intensity: true, classification: true };
    for (;;) {
      const chunk = reader.read(chunkSize, fields, { ...out, offset: reader.pointsRead });
      if (!chunk) break;
      const p = chunk.positions!;
      for (let i = 0; i < p.length; i += 3) {
        for (let a = 0; a < 3; a++) {
          const v = p[i + a];
          if (v < min[a]) min[a] = v;
          if (v > max[a]) max[a] = v;
        }
      }
      decodeMs += performance.now() - t0;
      options.onChunk?.(chunk, header);
      options.onProgress?.(reader.pointsRead, n);
      if (options.yieldBetweenChunks) await new Promise((r) => setTimeout(r, 0));
      if (options.signal?.aborted) throw new LasError(fileName, 'loading was cancelled');
      t0 = performance.now();
    }
    decodeMs += performance.now() - t0;
    if (n === 0) {
      min.fill(0);
      max.fill(0);
    }
    return { fileName, header, count: n, ...out, localBounds: { min, max }, decodeMs, warnings: reader.warnings };
  } finally {
    reader.close();
  }
}

/** Scaled coordinate of raw integer `X` on `axis`: X * scale + offset in float64, as laspy computes it. */
export function scaled(header: LasHeader, axis: 0 | 1 | 2, raw: number): number {
  return raw * header.scale[axis] + header.offset[axis];
}
