// What a level costs and knows, computed on the CPU for the store stream:
// the cost model (the per-level GPU state a surface over a pool of a given
// capacity takes, what a resident and a wanted chunk cost), range arrays read
// once, where refinement starts, and how an arrived chunk is put.
import { neighbourhoodRanges } from './plan.ts';
import type { LevelVolume } from './stream-port.ts';
import type { ZfpStore } from './zarr/store.ts';
import type { ChunkIndex, ChunkLevelLayout } from './types.ts';

/**
 * The Isosurface's per-volume buffers outside its budget over a pool of
 * `poolChunks` slots (src/isosurface/README.md, "Buffers": per block id its
 * ranges, neighbourhood range, masks, lists and cache map, about 40 B; per
 * slot 20 B; scratch), rounded up. Block ids are the pool's slots x blocks
 * per chunk: nothing here grows with the level.
 */
export function estimateFixedBytes(layout: ChunkLevelLayout, poolChunks: number): number {
  const ids = poolChunks * (layout.chunkEdge / 4) ** 3;
  return 48 * ids + 32 * poolChunks + (64 << 10);
}

export const chunkCount = (layout: ChunkLevelLayout) => layout.chunkGrid[0] * layout.chunkGrid[1] * layout.chunkGrid[2];

/**
 * The cost model (one place: the stream's plans, the page's choice of
 * refining by the view, tests). GPU bytes a resident chunk holds whatever
 * its surface: its pool slot and the surface's per-block state (a pool's
 * 64 KiB of scratch is not per chunk).
 */
export function residentChunkBytes(layout: ChunkLevelLayout): number {
  return layout.chunkBytes + estimateFixedBytes(layout, 1) - (64 << 10);
}

/**
 * A wanted chunk's share of its surface's cache and vertices before the
 * level's first surface says what it is: half its blocks active, each with
 * a cache slot and the vertices of a surface crossing it (384 B); a
 * cache-only surface (rays) only the slot and its bookkeeping (280 B).
 */
export function guessedSurfaceBytesPerChunk(layout: ChunkLevelLayout, cacheOnly = false): number {
  return (layout.chunkEdge / 4) ** 3 * 0.5 * (cacheOnly ? 280 : 384);
}

/** What a stream knows of a level's chunk ranges: the range array (read once) and the neighbourhood ranges the plan uses. */
export interface LevelRanges {
  index: number;
  layout: ChunkLevelLayout;
  /** [min, max] per chunk, or null while unknown. */
  ranges: Float32Array | null;
  /** Neighbourhood ranges per chunk, or null while unknown (every chunk needed). */
  nb: Float32Array | null;
  /** The range array being read. */
  reading: Promise<void> | null;
}

/** Reads a level's range array once (a failed read is tried again next time; rejects with its StoreError). */
export function readLevelRanges(store: ZfpStore, lv: LevelRanges): Promise<void> {
  if (lv.ranges || !store.levels[lv.index].rangesPath) return Promise.resolve();
  lv.reading ??= store.readRanges(lv.index).then(
    (r) => {
      if (r && !lv.ranges) {
        lv.ranges = r;
        lv.nb = neighbourhoodRanges(lv.layout.chunkGrid, r);
      }
    },
    (e) => {
      lv.reading = null;
      throw e;
    },
  );
  return lv.reading;
}

/** The store's value range: its metadata, else the first of these levels whose chunk ranges are known; null when none is. */
export function storeValueRange(store: ZfpStore, levels: readonly Pick<LevelRanges, 'ranges'>[]): [number, number] | null {
  if (store.valueRange) return store.valueRange;
  for (const l of levels) {
    if (!l.ranges) continue;
    let lo = Infinity;
    let hi = -Infinity;
    for (let i = 0; i < l.ranges.length; i += 2) {
      if (l.ranges[i] < lo) lo = l.ranges[i];
      if (l.ranges[i + 1] > hi) hi = l.ranges[i + 1];
    }
    if (lo <= hi) return [lo, hi];
  }
  return null;
}

/**
 * The coarsest level a surface can be drawn at: usable (not wider than a
 * surface can be) and with at least 2 voxels on every axis where level 0 has
 * them. A pyramid of a long thin volume ends in levels one voxel thick (a
 * 20480 x 32 x 32 store's level 5 is 640 x 1 x 1): they hold no cell, so a
 * surface starting there would be empty, and a cut rooted there would look
 * fine enough from afar to never go finer.
 */
export function coarsestDrawableLevel(levels: readonly { layout: Pick<ChunkLevelLayout, 'dims'>; unusable: string | null }[]): number {
  const base = levels[0].layout.dims;
  const holdsCells = (L: number) => levels[L].layout.dims.every((d, a) => d >= 2 || base[a] < 2);
  let L = levels.length - 1;
  while (L > 0 && (levels[L].unusable || !holdsCells(L))) L--;
  return L;
}

/**
 * Puts a chunk that arrived into its level's pool, the same way for both
 * engines: when the pool is full and no slot was set aside for it, the least
 * recently wanted resident chunk that `keep` does not hold (what the step
 * wants and what is on screen) goes first. `changed` is called before each
 * put or eviction (a stream's pool-change counter). Throws what put throws.
 */
export function putArrived(
  lv: { volume: LevelVolume | null; lru: Map<ChunkIndex, true> },
  chunk: ChunkIndex,
  bytes: Uint8Array,
  keep: (c: ChunkIndex) => boolean,
  changed: () => void,
): void {
  const v = lv.volume!;
  if (!v.has(chunk)) {
    if (v.freeCount === 0 && !v.isReserved(chunk)) {
      for (const c of lv.lru.keys()) {
        if (keep(c)) continue;
        changed();
        v.evict(c);
        lv.lru.delete(c);
        break;
      }
    }
    changed();
    v.put(chunk, bytes);
  }
  lv.lru.set(chunk, true);
}
