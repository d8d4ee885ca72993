// Streams a store's surface: the coarsest level first, then refinement of
// the current isovalue level by level. Per level: the chunks the surface
// needs (plan.ts), fetched nearest-first (fetch/), put into that level's
// pool of compressed chunks (ChunkedVolume, GPU side), and once every one is
// resident that level's Isosurface computes the surface, which replaces the
// coarser one. A new isovalue starts over from the finest level whose needed
// chunks are all resident (so scrubbing stays at full detail where it can),
// and aborts requests no longer needed (newest wins). Everything on the GPU
// stays within the budget: pools get half of it (coarsest first), the two
// live surfaces (shown and next) a quarter each for cache and vertices.
import type { ChunkFetcher } from './fetch/chunk-fetcher.ts';
import { chunksNeeded, nearestFirst, neighbourhoodRanges } from './plan.ts';
import type { ChunkIndex, ChunkLevelLayout } from './types.ts';
import { isAbort } from './zarr/errors.ts';
import type { ZfpStore } from './zarr/open-store.ts';

/** What the controller needs of a ChunkedVolume (src/zfp/chunked-volume.ts). */
export interface LevelVolume {
  readonly poolChunks: number;
  readonly poolBytes: number;
  readonly residentCount: number;
  has(chunk: ChunkIndex): boolean;
  put(chunk: ChunkIndex, bytes: Uint8Array): void;
  evict(chunk: ChunkIndex): void;
  destroy(): void;
}
/** What it needs of the surface statistics. */
export interface LevelStats {
  triangles: number;
  cacheBytes: number;
  vertexBytes: number;
  /** Per-volume buffers outside the Isosurface's budget (block and group ranges, maps): counted too. */
  fixedBytes?: number;
}
/** What it needs of an Isosurface over a LevelVolume. */
export interface LevelSurface<S extends LevelStats = LevelStats> {
  compute(iso: number): Promise<S>;
  /** The cap for cache and vertex buffers (Isosurface.setMemoryBudget). */
  setMemoryBudget?(bytes: number): void;
  /** [min, max] per block of the level (raster block order): the ranges of a store without range arrays. */
  readBlockRanges?(): Promise<Float32Array>;
  destroy(): void;
}
/** The GPU side, injected (the real one: gpu-port.ts; tests: a CPU fake). */
export interface StreamGpu<
  V extends LevelVolume = LevelVolume,
  S extends LevelStats = LevelStats,
  F extends LevelSurface<S> = LevelSurface<S>,
> {
  createVolume(layout: ChunkLevelLayout, poolChunks: number): V;
  createSurface(volume: V, memoryBudgetBytes: number): Promise<F>;
}

export interface StreamProgress {
  iso: number;
  level: number;
  chunksDone: number;
  chunksNeeded: number;
  /** Chunk bytes fetched so far (all levels, this store). */
  bytesFetched: number;
  phase: 'fetching' | 'computing' | 'shown' | 'stopped';
  /** Why refinement stopped above level 0 (phase 'stopped'). */
  reason?: string;
}

export interface ShownSurface<V, S extends LevelStats, F extends LevelSurface<S> = LevelSurface<S>> {
  level: number;
  iso: number;
  volume: V;
  surface: F;
  stats: S;
}

interface Waiting {
  level: number;
  iso: number;
  needed: number;
  missing: Set<ChunkIndex>;
  done: () => void;
}

interface Level<V> {
  index: number;
  layout: ChunkLevelLayout;
  /** [min, max] per chunk (the store's range array, or computed once the level was resident whole), or null. */
  ranges: Float32Array | null;
  /** Neighbourhood ranges per chunk, or null while unknown (every chunk needed). */
  nb: Float32Array | null;
  volume: V | null;
  /** Resident chunks, least recently needed first. */
  lru: Map<ChunkIndex, true>;
}

export class StreamController<
  V extends LevelVolume = LevelVolume,
  S extends LevelStats = LevelStats,
  F extends LevelSurface<S> = LevelSurface<S>,
> {
  readonly levels: Level<V>[];
  #gen = 0;
  #shown: ShownSurface<V, S, F> | null = null;
  #surfaces = new Map<number, F>();
  #lastStats = new Map<number, S>();
  #waiting: Waiting | null = null;
  #progress = new Set<(p: StreamProgress) => void>();
  #shownListeners = new Set<(s: ShownSurface<V, S, F>) => void>();
  #errors = new Set<(e: Error) => void>();
  #destroyed = false;
  /** Where "nearest first" measures from, in level-0 voxels (default: the volume's centre). */
  focus: [number, number, number];
  /**
   * The levels refinement may use: from `coarsest` down to `finest` (a
   * link's #level=, the CLI's --level L with both at L). Set before setIsovalue.
   */
  finest = 0;
  coarsest: number;

  private constructor(
    readonly store: ZfpStore,
    readonly fetcher: ChunkFetcher,
    readonly gpu: StreamGpu<V, S, F>,
    readonly budgetBytes: number,
    ranges: (Float32Array | null)[],
  ) {
    this.levels = store.levels.map((l, i) => ({
      index: i,
      layout: l.layout,
      volume: null,
      lru: new Map(),
      ranges: ranges[i],
      nb: ranges[i] ? neighbourhoodRanges(l.layout.chunkGrid, ranges[i]!) : null,
    }));
    this.coarsest = this.levels.length - 1;
    const d = store.levels[0].layout.dims;
    this.focus = [d[0] / 2, d[1] / 2, d[2] / 2];
    fetcher.onChunk((level, chunk, bytes) => this.#arrived(level, chunk, bytes));
    fetcher.onError((level, chunk, e) => {
      for (const l of this.#errors) l(e);
      if (this.#waiting?.level === level && this.#waiting.missing.has(chunk)) this.#stop(level, e.message);
    });
  }

  /** Reads the range arrays (metadata), then the controller is ready for setIsovalue. */
  static async create<V extends LevelVolume, S extends LevelStats, F extends LevelSurface<S>>(
    store: ZfpStore,
    fetcher: ChunkFetcher,
    gpu: StreamGpu<V, S, F>,
    budgetBytes: number,
  ): Promise<StreamController<V, S, F>> {
    const ranges = await Promise.all(store.levels.map((_, i) => store.readRanges(i)));
    return new StreamController(store, fetcher, gpu, budgetBytes, ranges);
  }

  onProgress(l: (p: StreamProgress) => void): () => void {
    this.#progress.add(l);
    return () => this.#progress.delete(l);
  }
  onShown(l: (s: ShownSurface<V, S, F>) => void): () => void {
    this.#shownListeners.add(l);
    return () => this.#shownListeners.delete(l);
  }
  onError(l: (e: Error) => void): () => void {
    this.#errors.add(l);
    return () => this.#errors.delete(l);
  }

  get shown(): ShownSurface<V, S, F> | null {
    return this.#shown;
  }

  /** [min, max] per chunk of a level, when known (range arrays, or computed once the level was resident whole). */
  chunkRanges(level: number): Float32Array | null {
    return this.levels[level]?.ranges ?? null;
  }

  /** The store's value range: its metadata, else the finest level whose chunk ranges are known; null when none is. */
  get valueRange(): [number, number] | null {
    if (this.store.valueRange) return this.store.valueRange;
    for (const l of this.levels) {
      if (!l.ranges) continue;
      let lo = Infinity,
        hi = -Infinity;
      for (let i = 0; i < l.ranges.length; i += 2) {
        if (l.ranges[i] < lo) lo = l.ranges[i];
        if (l.ranges[i + 1] > hi) hi = l.ranges[i + 1];
      }
      if (lo <= hi) return [lo, hi];
    }
    return null;
  }

  /** GPU bytes accounted: every pool plus the live surfaces' cache and vertex buffers. */
  get gpuBytes(): { pools: number; surfaces: number; total: number } {
    let pools = 0;
    for (const l of this.levels) pools += l.volume?.poolBytes ?? 0;
    let surfaces = 0;
    for (const [level] of this.#surfaces) {
      const s = this.#lastStats.get(level);
      // an Isosurface's fixed bytes include its source's pool, counted above
      if (s) surfaces += s.cacheBytes + s.vertexBytes + Math.max(0, (s.fixedBytes ?? 0) - (this.levels[level].volume?.poolBytes ?? 0));
    }
    return { pools, surfaces, total: pools + surfaces };
  }

  /** Newest wins: resolves when this isovalue's refinement ends (finest level reached, stopped, or superseded). */
  async setIsovalue(iso: number): Promise<void> {
    const gen = ++this.#gen;
    this.#waiting?.done();
    this.#waiting = null;
    // abort requests this isovalue does not need (newest wins); keep the rest
    const neededAt = new Map<number, Set<ChunkIndex> | null>();
    this.fetcher.retain((level, chunk) => {
      if (!neededAt.has(level)) {
        const nb = this.levels[level]?.nb;
        neededAt.set(level, nb ? new Set(chunksNeeded(nb, iso)) : null);
      }
      const set = neededAt.get(level);
      return set === null || set!.has(chunk);
    });
    const coarsest = Math.min(this.coarsest, this.levels.length - 1);
    const finest = Math.max(0, Math.min(this.finest, coarsest));
    // the finest level already able to show this isovalue without fetching
    let start = coarsest;
    for (let L = finest; L < coarsest; L++) {
      const lv = this.levels[L];
      if (lv.volume && lv.nb && chunksNeeded(lv.nb, iso).every((c) => lv.volume!.has(c))) {
        start = L;
        break;
      }
    }
    for (let L = start; L >= finest; L--) {
      if (gen !== this.#gen || this.#destroyed) return;
      const ok = await this.#refine(L, iso, gen);
      if (!ok) return;
    }
  }

  async #refine(L: number, iso: number, gen: number): Promise<boolean> {
    const lv = this.levels[L];
    const pool = this.#ensureVolume(lv);
    if (!pool)
      return this.#stop(
        L,
        `level ${L} does not fit: its pool of compressed chunks (${lv.layout.chunkBytes} bytes each) gets no room in the budget of ${mib(this.budgetBytes)} MiB`,
      );
    let needed = lv.nb ? chunksNeeded(lv.nb, iso) : allChunks(lv.layout);
    if (needed.length > pool.poolChunks) {
      return this.#stop(
        L,
        `level ${L} needs ${needed.length} chunks (${mib(needed.length * lv.layout.chunkBytes)} MiB) at iso ${iso}${lv.nb ? '' : ' (no range arrays: every chunk)'}, its pool holds ${pool.poolChunks} within the budget of ${mib(this.budgetBytes)} MiB`,
      );
    }
    const s = 1 / 2 ** L;
    needed = nearestFirst(lv.layout, needed, [this.focus[0] * s, this.focus[1] * s, this.focus[2] * s]);
    for (const c of needed)
      if (lv.lru.has(c)) {
        lv.lru.delete(c);
        lv.lru.set(c, true);
      }
    const missing = new Set(needed.filter((c) => !pool.has(c)));
    const progress = (phase: StreamProgress['phase']) =>
      this.#emit({
        iso,
        level: L,
        chunksDone: needed.length - missing.size,
        chunksNeeded: needed.length,
        bytesFetched: this.fetcher.counters.bytesFetched,
        phase,
      });
    if (missing.size > 0) {
      const wanted = new Set(needed);
      let mine: Waiting | null = null;
      await new Promise<void>((resolve) => {
        mine = this.#waiting = { level: L, iso, needed: needed.length, missing, done: resolve };
        // evict chunks this surface does not need first, so arrivals find room
        this.fetcher.want(
          L,
          needed.filter((c) => missing.has(c)),
        );
        this.#makeRoom(lv, missing.size, wanted);
        progress('fetching');
        if (missing.size === 0) resolve();
      });
      if (this.#waiting === mine) this.#waiting = null; // a newer isovalue may already wait
      if (gen !== this.#gen || this.#destroyed) return false;
      if (missing.size > 0) return false; // stopped by a failed chunk
    }
    progress('computing');
    let surface = this.#surfaces.get(L);
    try {
      // each of the (at most two) live surfaces: fixed buffers + cache + vertices within a quarter
      const quarter = Math.floor(this.budgetBytes / 4);
      if (!surface) {
        const fixed = estimateFixedBytes(lv.layout);
        if (quarter - fixed < MIN_SURFACE_BYTES) {
          return this.#stop(
            L,
            `level ${L}'s surface needs about ${mib(fixed)} MiB of per-block buffers (ranges, maps) besides its cache and vertices; a quarter of the budget of ${mib(this.budgetBytes)} MiB does not hold them`,
          );
        }
        surface = await this.gpu.createSurface(pool, quarter - fixed);
        this.#surfaces.set(L, surface);
      }
      let stats = await surface.compute(iso);
      const actualFixed = Math.max(0, (stats.fixedBytes ?? 0) - pool.poolBytes);
      if (actualFixed > estimateFixedBytes(lv.layout)) {
        // the estimate was short: tighten the cap, or give the level up
        if (quarter - actualFixed < MIN_SURFACE_BYTES || !surface.setMemoryBudget) {
          surface.destroy();
          this.#surfaces.delete(L);
          return this.#stop(
            L,
            `level ${L}'s surface holds ${mib(actualFixed)} MiB of per-block buffers; a quarter of the budget of ${mib(this.budgetBytes)} MiB does not hold them with a cache`,
          );
        }
        surface.setMemoryBudget(quarter - actualFixed);
        if (stats.cacheBytes + stats.vertexBytes + actualFixed > quarter) stats = await surface.compute(iso);
      }
      this.#lastStats.set(L, stats);
      // A store without range arrays: the level was fetched whole; its chunk
      // ranges come from the GPU's block ranges, so the next isovalue fetches
      // only what it needs.
      if (!lv.nb && surface.readBlockRanges && pool.residentCount === chunkCount(lv.layout)) {
        lv.ranges = chunkRangesOfBlocks(lv.layout, await surface.readBlockRanges());
        lv.nb = neighbourhoodRanges(lv.layout.chunkGrid, lv.ranges);
      }
      if (gen !== this.#gen || this.#destroyed) return false;
      this.#show({ level: L, iso, volume: pool, surface, stats });
      progress('shown');
      return true;
    } catch (e) {
      if (isAbort(e) || (e as Error).name === 'IsosurfaceSupersededError') return false;
      // a surface over its budget is the pipeline's clear refusal: the finer level stops, the coarser stays
      if ((e as Error).name === 'IsosurfaceBudgetError') return this.#stop(L, (e as Error).message);
      for (const l of this.#errors) l(e as Error);
      return this.#stop(L, (e as Error).message);
    }
  }

  #show(s: ShownSurface<V, S, F>): void {
    const old = this.#shown;
    this.#shown = s;
    for (const l of this.#shownListeners) l(s);
    // keep two surfaces at most: the one shown and (if different) none other
    for (const [level, surf] of this.#surfaces) {
      if (level !== s.level && level !== old?.level) {
        surf.destroy();
        this.#surfaces.delete(level);
        this.#lastStats.delete(level);
      }
    }
    if (old && old.level !== s.level) {
      old.surface.destroy();
      this.#surfaces.delete(old.level);
      this.#lastStats.delete(old.level);
    }
  }

  #stop(level: number, reason: string): false {
    const w = this.#waiting;
    this.#waiting = null;
    if (w) {
      this.fetcher.want(level, []);
      w.done();
    }
    this.#emit({
      iso: this.#shown?.iso ?? NaN,
      level,
      chunksDone: 0,
      chunksNeeded: 0,
      bytesFetched: this.fetcher.counters.bytesFetched,
      phase: 'stopped',
      reason,
    });
    return false;
  }

  #emit(p: StreamProgress): void {
    for (const l of this.#progress) l(p);
  }

  #ensureVolume(lv: Level<V>): V | null {
    if (lv.volume) return lv.volume;
    let used = 0;
    for (const l of this.levels) used += l.volume?.poolBytes ?? 0;
    const room = Math.floor(this.budgetBytes / 2) - used;
    const count = lv.layout.chunkGrid[0] * lv.layout.chunkGrid[1] * lv.layout.chunkGrid[2];
    // page table: 4 bytes per chunk of the level; the rest is the pool
    const capacity = Math.min(count, Math.floor((room - 4 * count - 256) / lv.layout.chunkBytes));
    if (capacity <= 0) return null;
    lv.volume = this.gpu.createVolume(lv.layout, capacity);
    return lv.volume;
  }

  #makeRoom(lv: Level<V>, count: number, keep: Set<ChunkIndex>): void {
    const v = lv.volume!;
    let free = v.poolChunks - v.residentCount;
    for (const c of [...lv.lru.keys()]) {
      if (free >= count) break;
      if (keep.has(c)) continue;
      v.evict(c);
      lv.lru.delete(c);
      free++;
    }
  }

  #arrived(level: number, chunk: ChunkIndex, bytes: Uint8Array): void {
    const lv = this.levels[level];
    const w = this.#waiting;
    if (!lv?.volume || w?.level !== level || !w.missing.has(chunk)) return;
    if (!lv.volume.has(chunk)) {
      if (lv.volume.residentCount >= lv.volume.poolChunks) this.#makeRoom(lv, 1, w.missing);
      try {
        lv.volume.put(chunk, bytes);
      } catch (e) {
        for (const l of this.#errors) l(e as Error);
        this.#stop(level, (e as Error).message);
        return;
      }
    }
    lv.lru.set(chunk, true);
    w.missing.delete(chunk);
    this.#emit({
      iso: w.iso,
      level,
      chunksDone: w.needed - w.missing.size,
      chunksNeeded: w.needed,
      bytesFetched: this.fetcher.counters.bytesFetched,
      phase: 'fetching',
    });
    if (w.missing.size === 0) w.done();
  }

  destroy(): void {
    this.#destroyed = true;
    this.#gen++;
    this.fetcher.cancelAll();
    this.#waiting?.done();
    for (const s of this.#surfaces.values()) s.destroy();
    this.#surfaces.clear();
    for (const l of this.levels) {
      l.volume?.destroy();
      l.volume = null;
    }
    this.#shown = null;
  }
}

/** Below this, a surface's cache and vertex buffers are too small to be worth creating. */
const MIN_SURFACE_BYTES = 256 << 10;

/**
 * The Isosurface's per-volume buffers outside its budget (src/isosurface/README.md,
 * "Buffers": ranges, neighbourhood ranges, masks, lists and maps per block,
 * about 40 B; per group (= chunk) 20 B; scratch), rounded up.
 */
export function estimateFixedBytes(layout: ChunkLevelLayout): number {
  const blocks = layout.dims.reduce((a, n) => a * Math.ceil(n / 4), 1);
  const chunks = layout.chunkGrid[0] * layout.chunkGrid[1] * layout.chunkGrid[2];
  return 48 * blocks + 32 * chunks + (64 << 10);
}

const chunkCount = (layout: ChunkLevelLayout) => layout.chunkGrid[0] * layout.chunkGrid[1] * layout.chunkGrid[2];

function allChunks(layout: ChunkLevelLayout): ChunkIndex[] {
  return Array.from({ length: chunkCount(layout) }, (_, i) => i);
}

/** [min, max] per chunk from [min, max] per 4^3 block (raster block order of the level). */
export function chunkRangesOfBlocks(layout: ChunkLevelLayout, blockRanges: Float32Array): Float32Array {
  const bg = layout.dims.map((n) => Math.ceil(n / 4));
  const [gx, gy] = layout.chunkGrid;
  const per = layout.chunkEdge / 4;
  const out = new Float32Array(2 * chunkCount(layout));
  for (let i = 0; i < out.length; i += 2) {
    out[i] = Infinity;
    out[i + 1] = -Infinity;
  }
  for (let bz = 0; bz < bg[2]; bz++) {
    for (let by = 0; by < bg[1]; by++) {
      for (let bx = 0; bx < bg[0]; bx++) {
        const b = bx + bg[0] * (by + bg[1] * bz);
        const c = Math.floor(bx / per) + gx * (Math.floor(by / per) + gy * Math.floor(bz / per));
        const lo = blockRanges[2 * b],
          hi = blockRanges[2 * b + 1];
        if (lo < out[2 * c]) out[2 * c] = lo;
        if (hi > out[2 * c + 1]) out[2 * c + 1] = hi;
      }
    }
  }
  return out;
}
const mib = (b: number) => (b / 2 ** 20).toFixed(1);
