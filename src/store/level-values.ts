// A small level read whole at open, before any surface (issue 37): a store
// with no value range in its metadata and no range arrays (the layout of the
// published collections) would otherwise show a slider of [0, 1] until a
// level is resident whole, which a view's cut never makes. The coarsest
// level is a chunk or a few: its chunks are read through the store and
// decoded on the CPU (zfp chunks with the CPU codec, bricks of lossless
// chunks arrive as values), giving the level's value range and its block
// ranges (the slider's profile and the first isovalue's choice). The range
// is provisional: finer levels may reach further.
import { blockRanges, decodeVolume, toWords } from '../zfp/cpu/codec.ts';
import { openZfpStream } from '../zfp/format.ts';
import type { ChunkIndex } from './types.ts';
import type { ZfpStore } from './zarr/store.ts';

export interface LevelValues {
  level: number;
  dims: [number, number, number];
  /** [min, max] of the level's finite values, or null when it has none. */
  valueRange: [number, number] | null;
  /** [min, max] per 4^3 block of the level, raster block order (x fastest). */
  blockRanges: Float32Array;
  /** Bytes read for it. */
  bytes: number;
}

/** What is read whole at most: a level's chunks and decoded values. */
export const LEVEL_VALUES_LIMITS = { maxChunks: 64, maxValues: 2 ** 24 };

/**
 * Reads level `level` whole and decodes it on the CPU; null when the level
 * is larger than LEVEL_VALUES_LIMITS. Rejects with the store's error when a
 * chunk cannot be read.
 */
export async function readLevelValues(store: ZfpStore, level: number, signal?: AbortSignal): Promise<LevelValues | null> {
  const lv = store.levels[level];
  const { dims, chunkEdge: C, chunkGrid: g, arrivesAs } = lv.layout;
  const [X, Y, Z] = dims;
  if (lv.chunkCount > LEVEL_VALUES_LIMITS.maxChunks || X * Y * Z > LEVEL_VALUES_LIMITS.maxValues) return null;
  const out = new Float32Array(X * Y * Z);
  let bytes = 0;
  const chunks: ChunkIndex[] = Array.from({ length: lv.chunkCount }, (_, i) => i);
  const read = await Promise.all(chunks.map((c) => store.readChunk(level, c, signal ? { signal } : undefined)));
  for (const c of chunks) {
    const raw = read[c];
    bytes += store.isAbsent(raw) ? 0 : raw.byteLength;
    let values: Float32Array;
    if (arrivesAs === 'float32') {
      values = new Float32Array(raw.buffer.slice(raw.byteOffset, raw.byteOffset + raw.byteLength));
    } else {
      const info = openZfpStream(raw, `${store.name} level ${level} chunk ${c}`);
      values = decodeVolume(toWords(raw), [C, C, C], info.bitsPerBlock, info.payloadBitOffset);
    }
    const x0 = (c % g[0]) * C;
    const y0 = (Math.floor(c / g[0]) % g[1]) * C;
    const z0 = Math.floor(c / (g[0] * g[1])) * C;
    // edge chunks are stored whole: only their voxels inside the level count
    for (let z = 0; z < Math.min(C, Z - z0); z++)
      for (let y = 0; y < Math.min(C, Y - y0); y++) {
        const from = C * (y + C * z);
        out.set(values.subarray(from, from + Math.min(C, X - x0)), x0 + X * (y0 + y + Y * (z0 + z)));
      }
  }
  const ranges = blockRanges(out, [X, Y, Z]);
  let lo = Infinity;
  let hi = -Infinity;
  for (let i = 0; i < ranges.length; i += 2) {
    // blocks with no finite value hold the empty range [FLT_MAX, -FLT_MAX]
    if (ranges[i] <= ranges[i + 1]) {
      if (ranges[i] < lo) lo = ranges[i];
      if (ranges[i + 1] > hi) hi = ranges[i + 1];
    }
  }
  return { level, dims: [X, Y, Z], valueRange: lo <= hi ? [lo, hi] : null, blockRanges: ranges, bytes };
}
