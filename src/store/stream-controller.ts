// Streams a store's surface: the coarsest level first, then refinement of
// the current isovalue level by level. Per level: the chunks the surface
// needs (plan.ts), fetched nearest-first (fetch/), put into that level's
// pool of compressed chunks (ChunkedVolume, GPU side), and once every one is
// resident that level's Isosurface computes the surface, which replaces the
// coarser one. A new isovalue starts over from the finest level whose needed
// chunks are all resident (so scrubbing stays at full detail where it can),
// and aborts requests no longer needed (newest wins).
//
// One budget, spent where needed: everything the stream holds on the GPU
// (pools, surfaces with their per-level buffers, cache, vertices, scratch)
// is counted where it is made (the port's allocatedBytes) and stays within
// the budget. A level's pool holds the chunks its surface needs (it grows
// and shrinks with the isovalue) and its surface gets the rest; when room
// runs short, pools of levels that are not on screen go first (their chunks
// stay in the fetcher's CPU cache).
//
// A chunk that fails (after the store's own retries) leaves the coarser
// surface on screen: the refinement stops with the reason, and once the
// chunk's cool-down has passed the onRetry listeners are told (the page asks
// for the same isovalue again; the CLI reports the failure instead).
import { StreamEvents } from './stream-events.ts';
import type { ChunkFetcher } from './fetch/chunk-fetcher.ts';
import { LearntRanges, learnSlotRanges } from './learnt-ranges.ts';
import {
  allChunks,
  chunkCount,
  chunkRangesOfIds,
  coarsestDrawableLevel,
  estimateFixedBytes,
  putArrived,
  readLevelRanges,
  storeValueRange,
} from './level-state.ts';
import { chunksNeeded, nearestFirst, neighbourhoodRanges } from './plan.ts';
import type { LevelStats, LevelSurface, LevelVolume, ShownSurface, StreamGpu, StreamGpuBytes, StreamProgress } from './stream-port.ts';
import type { ChunkIndex, ChunkLevelLayout } from './types.ts';

export type { LevelStats, LevelSurface, LevelVolume, ShownSurface, StreamGpu, StreamGpuBytes, StreamProgress };
export { chunkRangesOfIds, estimateFixedBytes };
import { isAbort } from './zarr/errors.ts';
import type { ZfpStore } from './zarr/open-store.ts';

interface Waiting {
  level: number;
  iso: number;
  needed: number;
  missing: Set<ChunkIndex>;
  /** The chunks the surface needs (an arrival never evicts one of them). */
  wanted: ReadonlySet<ChunkIndex>;
  done: () => void;
}

interface Level<V> {
  index: number;
  layout: ChunkLevelLayout;
  /** [min, max] per chunk (the store's range array, read when the level is first needed, or computed once the level was resident whole), or null. */
  ranges: Float32Array | null;
  /** The range array being read (a level's are read when refinement first reaches it). */
  reading: Promise<void> | null;
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
  /** Chunk ranges learnt as chunks arrive, for levels without range arrays (learnt-ranges.ts; shared with the view stream). */
  readonly learnt: LearntRanges;
  /** Chunks put into or evicted from any pool so far: a surface's block ranges are its slots' chunks' while this is unchanged. */
  #poolChanges = 0;
  #gen = 0;
  #shown: ShownSurface<V, S, F> | null = null;
  #surfaces = new Map<number, F>();
  #lastStats = new Map<number, S>();
  /** GPU bytes each level's surface held when last shown, besides the pool (per-level buffers, cache, vertices). */
  #footprint = new Map<number, number>();
  /** Surfaces being made, per level (so two refinements never make two for one level). */
  #creating = new Map<number, Promise<F>>();
  /** The pool capacity each surface was made for. */
  #surfaceCapacity = new WeakMap<F, number>();
  #retired: F | null = null;
  #waiting: Waiting | null = null;
  readonly #events = new StreamEvents<ShownSurface<V, S, F>>();
  #retryListeners = new Set<(iso: number) => void>();
  #retryTimer: ReturnType<typeof setTimeout> | null = null;
  /** The isovalue of the newest setIsovalue. */
  #iso = NaN;
  #destroyed = false;
  /** The whole stream's GPU memory: pools, surfaces, everything (applies from the next step on when changed). */
  budgetBytes: number;
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
    budgetBytes: number,
    learnt?: LearntRanges,
  ) {
    this.budgetBytes = budgetBytes;
    const grids = store.levels.map((l) => l.layout.chunkGrid);
    this.learnt = learnt?.fits(grids) ? learnt : new LearntRanges(grids);
    this.levels = store.levels.map((l, i) => ({
      index: i,
      layout: l.layout,
      volume: null,
      lru: new Map(),
      ranges: null,
      reading: null,
      nb: null,
    }));
    // ranges learnt earlier in the session (the same store opened again): planned with from the start
    for (const lv of this.levels) this.#applyLearnt(lv);
    this.coarsest = coarsestDrawableLevel(store.levels);
    const d = store.levels[0].layout.dims;
    this.focus = [d[0] / 2, d[1] / 2, d[2] / 2];
    fetcher.onChunk((level, chunk, bytes) => this.#arrived(level, chunk, bytes));
    fetcher.onError((level, chunk, e, repeated) => {
      if (!repeated) this.#events.error(e);
      const w = this.#waiting;
      if (w?.level !== level || !w.missing.has(chunk)) return;
      const at = fetcher.retryAt(level, chunk);
      const inMs = at === undefined ? undefined : Math.max(0, at - performance.now());
      this.#stop(level, e.message, 'chunk', inMs);
      if (inMs !== undefined) this.#scheduleRetry(w.iso, inMs);
    });
  }

  /**
   * Reads the coarsest level's range array, then the controller is ready for
   * setIsovalue. A finer level's is read when refinement first reaches it,
   * so opening costs the same whatever the store's size.
   */
  static async create<V extends LevelVolume, S extends LevelStats, F extends LevelSurface<S>>(
    store: ZfpStore,
    fetcher: ChunkFetcher,
    gpu: StreamGpu<V, S, F>,
    budgetBytes: number,
    options: { learnt?: LearntRanges } = {},
  ): Promise<StreamController<V, S, F>> {
    const c = new StreamController(store, fetcher, gpu, budgetBytes, options.learnt);
    await c.#readRanges(c.levels[c.levels.length - 1]);
    return c;
  }

  /** The level's range array, read once (a failed read is tried again next time; rejects with its StoreError). */
  #readRanges(lv: Level<V>): Promise<void> {
    return readLevelRanges(this.store, lv);
  }

  onProgress(l: (p: StreamProgress) => void): () => void {
    return this.#events.onProgress(l);
  }
  onShown(l: (s: ShownSurface<V, S, F>) => void): () => void {
    return this.#events.onShown(l);
  }
  /** Chunk failures (each once, not its repeats during the cool-down) and GPU errors. */
  onError(l: (e: Error) => void): () => void {
    return this.#events.onError(l);
  }
  /** A refinement stopped by a failed chunk may be tried again now, at this isovalue (still the newest). */
  onRetry(l: (iso: number) => void): () => void {
    this.#retryListeners.add(l);
    return () => this.#retryListeners.delete(l);
  }

  get shown(): ShownSurface<V, S, F> | null {
    return this.#shown;
  }

  /** [min, max] per chunk of a level, when known for every chunk (range arrays, or every chunk's learnt). */
  chunkRanges(level: number): Float32Array | null {
    const lv = this.levels[level];
    if (!lv?.ranges) return null;
    return this.store.levels[level].rangesPath || this.learnt.knownCount(level) === chunkCount(lv.layout) ? lv.ranges : null;
  }

  /** The store's value range: its metadata, else the finest level whose chunk ranges are known; null when none is. */
  get valueRange(): [number, number] | null {
    return storeValueRange(this.store, this.levels);
  }

  /** GPU bytes held now (counted where they are made), split into pools and surfaces. */
  get gpuBytes(): StreamGpuBytes {
    let pools = 0;
    for (const l of this.levels) pools += l.volume?.poolBytes ?? 0;
    let cache = 0;
    let vertices = 0;
    for (const [level] of this.#surfaces) {
      const st = this.#lastStats.get(level);
      if (st) {
        cache += st.cacheBytes;
        vertices += st.vertexBytes;
      }
    }
    const total = this.gpu.allocatedBytes;
    return { pools, surfaces: total - pools, total, cache, vertices };
  }

  /** Newest wins: resolves when this isovalue's refinement ends (finest level reached, stopped, or superseded). */
  async setIsovalue(iso: number): Promise<void> {
    const gen = ++this.#gen;
    this.#iso = iso;
    this.#clearRetry();
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
    let shown = false;
    for (let L = start; L >= finest; L--) {
      if (gen !== this.#gen || this.#destroyed) return;
      const step = await this.#refine(L, iso, gen);
      if (step === 'shown') shown = true;
      if (step !== 'shown' && step !== 'skipped') {
        // A finer level that held the chunks could not show this isovalue (the budget): nothing on
        // screen is of this isovalue yet, so go coarse to fine up to it, as for any new isovalue.
        if (!shown && start < coarsest && this.#shown?.iso !== iso && gen === this.#gen && !this.#destroyed) {
          for (let M = coarsest; M > start; M--) {
            if (gen !== this.#gen || this.#destroyed) return;
            const again = await this.#refine(M, iso, gen);
            if (again !== 'shown' && again !== 'skipped') return;
          }
        }
        return;
      }
    }
  }

  /**
   * A coarser level than the one on screen that finds no room (the finer
   * surface holds it) is skipped, not a stop: the finer surface stays until
   * the next finer level replaces it.
   */
  #skippable(L: number): boolean {
    const s = this.#shown;
    return s !== null && s.level < L && L > Math.max(0, Math.min(this.finest, this.coarsest));
  }

  /** Bytes free within the budget now (a little is kept for short-lived buffers: statistics, staging). */
  #free(): number {
    return this.budgetBytes - RESERVE_BYTES - this.gpu.allocatedBytes;
  }

  /**
   * Lets pools (and surfaces) of levels outside `keep` go, finest first,
   * until `bytes` are free; then, if still short, empties the block caches of
   * the surfaces that stay (a retired one first, then the others: their
   * drawn meshes stay, a cache regrows as a surface needs it). Whether the
   * bytes are free.
   */
  #release(bytes: number, keep: ReadonlySet<number>): boolean {
    for (let L = 0; L < this.levels.length && this.#free() < bytes; L++) {
      if (keep.has(L)) continue;
      const lv = this.levels[L];
      const surface = this.#surfaces.get(L);
      if (surface) {
        surface.destroy();
        this.#surfaces.delete(L);
        this.#lastStats.delete(L);
      }
      if (lv.volume) {
        this.#poolChanges++;
        lv.volume.destroy();
        lv.volume = null;
        lv.lru.clear();
      }
    }
    const kept = [...(this.#retired ? [this.#retired] : []), ...this.#surfaces.values()];
    for (const surface of kept) {
      if (this.#free() >= bytes) break;
      surface.trimCache();
    }
    return this.#free() >= bytes;
  }

  /** Levels whose GPU state must stay: the one on screen and the one being refined. */
  #keep(L: number): Set<number> {
    const keep = new Set([L]);
    if (this.#shown) keep.add(this.#shown.level);
    return keep;
  }

  /** Held by the surface on screen when it is another level's (for messages). */
  #shownNote(L: number): string {
    const s = this.#shown;
    if (!s || s.level === L) return '';
    return ` besides level ${s.level} on screen`;
  }

  /**
   * Gives level L a pool of at least `n` chunks (grown, or made), and room
   * for its surface when it has none yet; a pool far larger than `n` gives
   * back what it does not need (chunks not in `wanted` evicted first).
   * Returns why it cannot, or null.
   */
  #fitPool(lv: Level<V>, needed: number, wanted: ReadonlySet<ChunkIndex>, iso: number): string | null {
    const L = lv.index;
    const n = Math.max(1, needed); // a pool holds one chunk at least (an isovalue outside the level needs none)
    const v = lv.volume;
    const have = v?.poolChunks ?? 0;
    // A surface is made for its pool's capacity: resizing the pool of a level that has one means a new
    // surface (the old one drawn meanwhile), so such a pool is not shrunk, and grows with some slack.
    const hasSurface = this.#surfaces.has(L) || this.#shown?.level === L;
    if (v && !hasSurface && have > 2 * n + 8) {
      const target = n;
      for (const c of [...lv.lru.keys()]) {
        if (v.residentCount <= target) break;
        if (wanted.has(c)) continue;
        v.evict(c);
        lv.lru.delete(c);
      }
      this.#poolChanges++;
      v.resize(Math.max(target, v.residentCount));
    }
    if (v && n <= v.poolChunks) return null;
    const chunks = chunkCount(lv.layout);
    const roomFor = (target: number) =>
      this.gpu.poolBytesFor(lv.layout, target) - (v?.poolBytes ?? 0) + estimateFixedBytes(lv.layout, target) + MIN_SURFACE_BYTES;
    let target = n;
    if (v && hasSurface) {
      const roomy = Math.min(chunks, Math.max(n, Math.ceil(have * 1.5)));
      if (this.#release(roomFor(roomy), this.#keep(L))) target = roomy;
    }
    const extra = this.gpu.poolBytesFor(lv.layout, target) - (v?.poolBytes ?? 0);
    const surfaceNeeds = estimateFixedBytes(lv.layout, target) + MIN_SURFACE_BYTES;
    if (!this.#release(extra + surfaceNeeds, this.#keep(L))) {
      const all = lv.nb ? '' : ' (no range arrays: every chunk)';
      return (
        `level ${L} needs ${n} chunks (${mib(n * lv.layout.chunkBytes)} MiB) at iso ${iso}${all}` +
        (surfaceNeeds ? ` and about ${mib(surfaceNeeds)} MiB for its surface's per-level buffers and a minimal cache` : '') +
        `; the budget of ${mib(this.budgetBytes)} MiB has ${mib(Math.max(0, this.#free()))} MiB free${this.#shownNote(L)}`
      );
    }
    if (v) {
      this.#poolChanges++;
      v.resize(target);
    } else lv.volume = this.gpu.createVolume(lv.layout, target);
    return null;
  }

  /**
   * The cap of level L's cache and vertex buffers: the budget less
   * everything else held now and, with `headroom`, less room for the next
   * coarser level's surface (a new isovalue shows it first while this one
   * stays on screen): what it took last time, else its per-level buffers and
   * a quarter of this surface's cache and vertices (a level has 4x fewer
   * surface cells than the next finer one).
   */
  #capFor(L: number, surface: F, headroom: boolean): number {
    let room = 0;
    const coarser = this.levels[L + 1];
    if (headroom && coarser && L + 1 <= this.coarsest && !this.#surfaces.has(L + 1)) {
      room =
        this.#footprint.get(L + 1) ??
        estimateFixedBytes(coarser.layout, coarser.volume?.poolChunks ?? chunkCount(coarser.layout)) + Math.ceil(surface.budgetedBytes / 4);
    }
    return this.budgetBytes - RESERVE_BYTES - room - (this.gpu.allocatedBytes - surface.budgetedBytes);
  }

  async #refine(L: number, iso: number, gen: number): Promise<'shown' | 'stopped' | 'skipped'> {
    const lv = this.levels[L];
    const unusable = this.store.levels[L].unusable;
    if (unusable) return this.#stop(L, unusable, 'limit');
    if (!lv.ranges) {
      try {
        await this.#readRanges(lv);
      } catch (e) {
        if (gen !== this.#gen || this.#destroyed) return 'stopped';
        this.#events.error(e as Error);
        return this.#stop(L, (e as Error).message, 'chunk');
      }
      if (gen !== this.#gen || this.#destroyed) return 'stopped';
    }
    let needed = lv.nb ? chunksNeeded(lv.nb, iso) : allChunks(lv.layout);
    const wanted = new Set(needed);
    const refused = this.#fitPool(lv, needed.length, wanted, iso);
    if (refused) return this.#skippable(L) ? 'skipped' : this.#stop(L, refused, 'budget');
    const pool = lv.volume!;
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
      let mine: Waiting | null = null;
      await new Promise<void>((resolve) => {
        mine = this.#waiting = { level: L, iso, needed: needed.length, missing, wanted, done: resolve };
        // evict chunks this surface does not need first, so arrivals find room
        const coming = needed.filter((c) => missing.has(c));
        pool.reserve(coming); // gives back what an older isovalue set aside
        this.#makeRoom(lv, missing.size, wanted);
        pool.reserve(coming);
        this.fetcher.want(
          L,
          needed.filter((c) => missing.has(c)),
        );
        progress('fetching');
        if (missing.size === 0) resolve();
      });
      if (this.#waiting === mine) this.#waiting = null; // a newer isovalue may already wait
      if (gen !== this.#gen || this.#destroyed) return 'stopped';
      if (missing.size > 0) return 'stopped'; // stopped by a failed chunk
    }
    progress('computing');
    // a surface being made for this level (by an older isovalue's refinement) is the one to use
    let surface = this.#surfaces.get(L) ?? (await this.#creating.get(L)?.catch(() => undefined));
    if (gen !== this.#gen || this.#destroyed) return 'stopped';
    if (surface && this.#surfaces.get(L) !== surface) surface = undefined; // let go meanwhile
    // A surface's per-block state is sized by its pool's capacity when it was
    // made (block ids are slot-relative): once the pool was resized it is
    // made again. The old one stays drawn, if it is on screen, until the new
    // one replaces it.
    if (surface && this.#surfaceCapacity.get(surface) !== pool.poolChunks) {
      this.#surfaces.delete(L);
      this.#lastStats.delete(L);
      if (this.#shown?.surface === surface) this.#retire(surface);
      else surface.destroy();
      surface = undefined;
    }
    try {
      if (!surface) {
        const fixed = estimateFixedBytes(lv.layout, pool.poolChunks);
        if (!this.#release(fixed + MIN_SURFACE_BYTES, this.#keep(L))) {
          if (this.#skippable(L)) return 'skipped';
          return this.#stop(
            L,
            `level ${L}'s surface needs about ${mib(fixed)} MiB of per-level buffers (ranges, maps) besides its cache and vertices; ` +
              `the budget of ${mib(this.budgetBytes)} MiB has ${mib(Math.max(0, this.#free()))} MiB free${this.#shownNote(L)}`,
            'budget',
          );
        }
        const making = this.gpu.createSurface(pool, Math.max(MIN_SURFACE_BYTES, this.#free() - fixed));
        this.#creating.set(L, making);
        try {
          surface = await making;
        } finally {
          if (this.#creating.get(L) === making) this.#creating.delete(L);
        }
        // the level's pool may have been let go meanwhile (a newer isovalue needed the room), or the controller closed
        if (this.#destroyed || lv.volume !== pool) {
          surface.destroy();
          return 'stopped';
        }
        this.#surfaces.set(L, surface);
        this.#surfaceCapacity.set(surface, pool.poolChunks);
      }
      if (gen !== this.#gen || this.#destroyed) return 'stopped';
      let stats: S;
      const changes = this.#poolChanges;
      try {
        surface.setMemoryBudget(Math.max(1, this.#capFor(L, surface, true)));
        stats = await surface.compute(iso);
      } catch (e) {
        // over its cap: without the room kept for a coarser surface, and with the pools of other levels let go, once more
        if ((e as Error).name !== 'IsosurfaceBudgetError' || gen !== this.#gen) throw e;
        this.#release(Infinity, this.#keep(L));
        surface.setMemoryBudget(Math.max(1, this.#capFor(L, surface, false)));
        stats = await surface.compute(iso);
      }
      this.#lastStats.set(L, stats);
      this.#footprint.set(L, Math.max(0, (stats.fixedBytes ?? 0) - pool.poolBytes) + stats.cacheBytes + stats.vertexBytes);
      // A level without range arrays: the ranges of the chunks this surface read are learnt from its block
      // ranges (as decoded), so the next isovalue fetches only what it needs (unknown chunks stay needed)
      if (!this.store.levels[L].rangesPath && gen === this.#gen && this.#poolChanges === changes)
        await this.#learn(L, pool, surface, changes);
      if (gen !== this.#gen || this.#destroyed) return 'stopped';
      this.#show({ level: L, iso, volume: pool, surface, stats });
      progress('shown');
      return 'shown';
    } catch (e) {
      // superseded: a newer isovalue may have let this level's surface go while it computed
      if (gen !== this.#gen || this.#destroyed) return 'stopped';
      if (isAbort(e) || (e as Error).name === 'IsosurfaceSupersededError') return 'stopped';
      // a surface over its budget is the pipeline's clear refusal: the finer level stops, the coarser stays
      if ((e as Error).name === 'IsosurfaceBudgetError')
        return this.#skippable(L) ? 'skipped' : this.#stop(L, (e as Error).message, 'budget');
      this.#events.error(e as Error);
      return this.#stop(L, (e as Error).message, 'gpu');
    }
  }

  #show(s: ShownSurface<V, S, F>): void {
    this.#shown = s;
    this.#events.shown(s);
    // one surface stays: the one shown now (the coarser one it replaces goes, and one made for a pool's old capacity)
    for (const [level, surf] of this.#surfaces) {
      if (level !== s.level) {
        surf.destroy();
        this.#surfaces.delete(level);
        this.#lastStats.delete(level);
      }
    }
    if (this.#retired && this.#retired !== s.surface) {
      this.#retired.destroy();
      this.#retired = null;
    }
  }

  /** A surface made for a pool's old capacity that is still on screen: destroyed when another one is shown. */
  #retire(surface: F): void {
    if (this.#retired && this.#retired !== surface) this.#retired.destroy();
    this.#retired = surface;
  }

  #stop(level: number, reason: string, cause: NonNullable<StreamProgress['cause']>, retryInMs?: number): 'stopped' {
    const w = this.#waiting;
    this.#waiting = null;
    if (w) {
      this.fetcher.want(level, []);
      w.done();
    }
    this.#events.stopped(this.#shown?.iso ?? Number.NaN, level, reason, cause, this.fetcher.counters.bytesFetched, retryInMs);
    return 'stopped';
  }

  #scheduleRetry(iso: number, inMs: number): void {
    this.#clearRetry();
    if (this.#retryListeners.size === 0) return;
    const gen = this.#gen;
    this.#retryTimer = setTimeout(() => {
      this.#retryTimer = null;
      if (gen !== this.#gen || this.#destroyed || iso !== this.#iso) return;
      for (const l of this.#retryListeners) l(iso);
    }, inMs + 50);
  }

  #clearRetry(): void {
    if (this.#retryTimer !== null) clearTimeout(this.#retryTimer);
    this.#retryTimer = null;
  }

  /**
   * Records the ranges of level L's resident chunks whose range is not known,
   * from the block ranges `surface` was just computed with (valid while no
   * chunk was put or evicted since: `changes`), then the level's ranges and
   * neighbourhood ranges as the plan reads them (NaN: unknown, needed).
   */
  async #learn(L: number, pool: V, surface: F, changes: number): Promise<void> {
    const lv = this.levels[L];
    const valid = () => this.#poolChanges === changes && !this.#destroyed;
    await learnSlotRanges(this.learnt, L, [...lv.lru.keys()], pool, surface, valid);
    this.#applyLearnt(lv);
  }

  /** A level without range arrays plans with its learnt ranges (NaN: unknown, needed), once any is known. */
  #applyLearnt(lv: Level<V>): void {
    const known = this.learnt.level(lv.index);
    if (this.store.levels[lv.index].rangesPath || !known || this.learnt.knownCount(lv.index) === 0) return;
    lv.ranges = known;
    lv.nb = neighbourhoodRanges(lv.layout.chunkGrid, known);
  }

  #emit(p: StreamProgress): void {
    this.#events.progress(p);
  }

  #makeRoom(lv: Level<V>, count: number, keep: ReadonlySet<ChunkIndex>): void {
    const v = lv.volume!;
    let free = v.freeCount;
    for (const c of [...lv.lru.keys()]) {
      if (free >= count) break;
      if (keep.has(c)) continue;
      this.#poolChanges++;
      v.evict(c);
      lv.lru.delete(c);
      free++;
    }
  }

  #arrived(level: number, chunk: ChunkIndex, bytes: Uint8Array): void {
    const lv = this.levels[level];
    const w = this.#waiting;
    if (!lv?.volume || w?.level !== level || !w.missing.has(chunk)) return;
    try {
      putArrived(
        lv,
        chunk,
        bytes,
        (c) => w.wanted.has(c),
        () => this.#poolChanges++,
      );
    } catch (e) {
      this.#events.error(e as Error);
      this.#stop(level, (e as Error).message, 'chunk');
      return;
    }
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
    this.#clearRetry();
    this.fetcher.cancelAll();
    this.#waiting?.done();
    for (const s of this.#surfaces.values()) s.destroy();
    this.#surfaces.clear();
    this.#retired?.destroy();
    this.#retired = null;
    for (const l of this.levels) {
      l.volume?.destroy();
      l.volume = null;
    }
    this.#shown = null;
  }
}

/** Kept free within the budget for short-lived buffers (statistics and readback staging, uniforms). */
const RESERVE_BYTES = 1 << 20;
/** Below this, a surface's cache and vertex buffers are too small to be worth creating. */
const MIN_SURFACE_BYTES = 256 << 10;

const mib = (b: number) => (b / 2 ** 20).toFixed(1);
