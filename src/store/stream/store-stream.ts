// The one stream of a store, for the page and the CLI, planned by the view
// or level by level (planner.ts); README.md says how it works. Each step the
// planner makes is fetched (what is not resident, nearest first), its levels'
// surfaces computed over their pools restricted to the drawn chunks (chunk
// roles), then shown whole (steps are snapshots). A new isovalue or view
// starts at the finest step already resident; the newest request wins and
// requests no longer needed are aborted. One budget for everything it holds
// on the GPU: a step that does not fit is tried once more with what is not
// on screen let go, then planned coarser (a planner that can), else the
// refinement stops there and says why, the coarser step staying on screen.
import type { ChunkFetcher } from '../fetch/chunk-fetcher.ts';
import { LearntRanges, learnSlotRanges } from '../learnt-ranges.ts';
import { coarsestDrawableLevel, storeValueRange } from '../level-state.ts';
import type { LevelStats, LevelSurface, StreamGpu, StreamGpuBytes, StreamProgress } from '../stream-port.ts';
import type { ChunkIndex } from '../types.ts';
import { isAbort } from '../zarr/errors.ts';
import { StreamEvents } from '../stream-events.ts';
import type { ZfpStore } from '../zarr/store.ts';
import type { ViewCut } from '../view/cut.ts';
import { CutPlanner } from './cut-planner.ts';
import type { Planner, StreamPlan } from './planner.ts';
import { StreamLevels } from './stream-levels.ts';
import { StreamSurfaces } from './stream-surfaces.ts';
import {
  type CutLevelShown,
  DEFAULT_TOLERANCE_PX,
  key,
  type LevelState,
  type RoleVolume,
  type ShownCut,
  type Step,
  showsStep,
  shownWanted as wantedOnScreen,
  type ViewSpec,
  type Waiting,
} from './stream-types.ts';

export { type CutLevelShown, DEFAULT_TOLERANCE_PX, type RoleVolume, type ShownCut, type Step, type ViewSpec };

export class StoreStream<V extends RoleVolume, S extends LevelStats, F extends LevelSurface<S>> {
  readonly levels: LevelState<V>[];
  /** Chunk ranges learnt as chunks arrive, for the levels without range arrays (learnt-ranges.ts). */
  readonly learnt: LearntRanges;
  /** The readbacks of learnt ranges in flight (learnSettled). */
  #learning: Promise<void> = Promise.resolve();
  /** Per level: ranges, pool, resident chunks, which chunks a surface needs, the cost model (stream-levels.ts). */
  readonly #pools: StreamLevels<V>;
  budgetBytes: number;
  finest = 0;
  coarsest: number;
  /** The finest level the cut may use: levels below it, or one between, cannot be drawn. */
  #finestUsable = 0;
  #view: ViewSpec | null = null;
  #iso = Number.NaN;
  #gen = 0;
  #destroyed = false;
  #shown: ShownCut<V, S, F> | null = null;
  readonly #surfaces: StreamSurfaces<V, S, F>;
  #waiting: Waiting | null = null;
  /** A refinement stopped by a failed chunk is tried again when the chunk has cooled down. */
  #retryTimer: ReturnType<typeof setTimeout> | null = null;
  /** Ghosts as skirts (ChunkedVolume's 'skirt' role): level seams covered by a one-cell overlap. */
  skirts = true;
  /** Whether failed chunks are tried again on their own (the page; the CLI reports the failure instead). */
  retryFailed = true;
  /**
   * Whether each step is drawn from copies of its surfaces (Isosurface.present): the page, which draws
   * while the next step computes; the CLI reads the surfaces once the refinement ended and needs none.
   */
  snapshots = true;
  readonly #events = new StreamEvents<ShownCut<V, S, F>>();

  private constructor(
    readonly store: ZfpStore,
    readonly fetcher: ChunkFetcher,
    readonly gpu: StreamGpu<V, S, F>,
    budgetBytes: number,
    /** What the steps draw: by view (view/cut-planner.ts) or level by level (level-planner.ts). */
    readonly planner: Planner,
    learnt?: LearntRanges,
  ) {
    this.budgetBytes = budgetBytes;
    // ranges learnt earlier in the session (the same store reopened at the same rate) carry over
    const grids = store.levels.map((l) => l.layout.chunkGrid);
    this.learnt = learnt?.fits(grids) ? learnt : new LearntRanges(grids);
    this.#pools = new StreamLevels(store, gpu, this.learnt);
    this.levels = this.#pools.levels;
    this.#surfaces = new StreamSurfaces(gpu);
    this.coarsest = coarsestDrawableLevel(store.levels);
    // levels finer than a level that cannot be drawn (wider than a surface can be) are never split into:
    // the cut stops there (the store's notes say which levels cannot be shown)
    this.#finestUsable = this.coarsest;
    while (this.#finestUsable > 0 && !store.levels[this.#finestUsable - 1].unusable) this.#finestUsable--;
    fetcher.onChunk((level, chunk, bytes) => this.#arrived(level, chunk, bytes));
    fetcher.onError((level, chunk, e, repeated) => {
      if (!repeated) this.#events.error(e);
      const w = this.#waiting;
      if (!w?.missing.has(key(level, chunk))) return;
      const at = fetcher.retryAt(level, chunk);
      const inMs = at === undefined ? undefined : Math.max(0, at - performance.now());
      this.#stop(level, e.message, 'chunk', inMs);
      // the coarser surface stays; once the chunk has cooled down, the same isovalue and view again
      if (inMs !== undefined && this.retryFailed) this.#scheduleRetry(inMs);
    });
  }

  /** A stream planned by `planner`, once the coarsest level's range array is read. */
  static async create<V extends RoleVolume, S extends LevelStats, F extends LevelSurface<S>>(
    store: ZfpStore,
    fetcher: ChunkFetcher,
    gpu: StreamGpu<V, S, F>,
    budgetBytes: number,
    planner: Planner,
    options: { learnt?: LearntRanges } = {},
  ): Promise<StoreStream<V, S, F>> {
    const v = new StoreStream(store, fetcher, gpu, budgetBytes, planner, options.learnt);
    await v.#pools.readRanges(v.coarsest);
    return v;
  }

  /** A stream refined by the view (setView before setIsovalue). */
  static byView<V extends RoleVolume, S extends LevelStats, F extends LevelSurface<S>>(
    store: ZfpStore,
    fetcher: ChunkFetcher,
    gpu: StreamGpu<V, S, F>,
    budgetBytes: number,
    options: { learnt?: LearntRanges } = {},
  ): Promise<StoreStream<V, S, F>> {
    return StoreStream.create(store, fetcher, gpu, budgetBytes, new CutPlanner(), options);
  }

  onProgress(l: (p: StreamProgress) => void): () => void {
    return this.#events.onProgress(l);
  }
  onShown(l: (s: ShownCut<V, S, F>) => void): () => void {
    return this.#events.onShown(l);
  }
  onError(l: (e: Error) => void): () => void {
    return this.#events.onError(l);
  }

  get shown(): ShownCut<V, S, F> | null {
    return this.#shown;
  }

  /** GPU bytes held now (counted where they are made): pools, surfaces, and of these the cache and vertex buffers. */
  get gpuBytes(): StreamGpuBytes {
    const pools = this.#pools.poolBytes;
    const total = this.gpu.allocatedBytes;
    const shown = this.#shown?.levels ?? [];
    return {
      pools,
      surfaces: total - pools,
      total,
      cache: shown.reduce((a, l) => a + l.stats.cacheBytes, 0),
      vertices: shown.reduce((a, l) => a + l.stats.vertexBytes, 0),
    };
  }

  /** [min, max] per chunk of a level, when read. */
  chunkRanges(level: number): Float32Array | null {
    return this.levels[level]?.ranges ?? null;
  }

  /** [min, max] of the store's values: its metadata, else the coarsest level's chunk ranges. */
  get valueRange(): [number, number] | null {
    return storeValueRange(this.store, [...this.levels].reverse());
  }

  /** A new camera (or tolerance): the cut is planned again at the current isovalue; resolves when that refinement ends. */
  setView(view: ViewSpec): Promise<void> {
    this.#view = view;
    return Number.isFinite(this.#iso) ? this.setIsovalue(this.#iso) : Promise.resolve();
  }

  /** Newest wins: resolves when this isovalue's refinement (for the current view) ends: the whole plan shown, stopped, or superseded. */
  async setIsovalue(iso: number): Promise<void> {
    const gen = ++this.#gen;
    this.#iso = iso;
    this.#waiting?.done();
    this.#waiting = null;
    if (!this.#view && this.planner.needsView) throw new Error('StoreStream: setView before setIsovalue');
    // A step that does not fit (a pool that cannot grow, a surface over its cap) is tried once more with
    // what is not on screen let go, then made coarser: planned again with what the surfaces really took
    // (the cost model) and less of the budget each time; the coarser step stays on screen meanwhile.
    let share = PLAN_SHARE;
    for (let attempt = 0; ; attempt++) {
      const r = await this.#refine(iso, gen, share);
      if (r === 'done' || gen !== this.#gen || this.#destroyed) return;
      // what the step that did not fit made goes; what is on screen stays
      this.#releaseUnshown();
      if ((r.coarser || attempt === 0) && attempt < MAX_COARSENINGS) {
        if (r.coarser) share *= 0.85;
        continue;
      }
      this.#stop(r.level, r.reason, 'budget');
      return;
    }
  }

  /** Plans with `share` of the budget and shows the plan's steps; 'done', or a step that did not fit. */
  async #refine(iso: number, gen: number, share: number): Promise<'done' | BudgetStop> {
    const stale = () => gen !== this.#gen || this.#destroyed;
    for (;;) {
      const plan = this.#plan(iso, share);
      if (plan.steps.length === 0) {
        // nothing the plan can draw: a level it cannot reach, or range arrays to read first
        if (plan.wantsRanges.length === 0) {
          if (plan.refused) this.#stop(plan.refused.level, plan.refused.reason, 'limit');
          return 'done';
        }
        if (!(await this.#readWanted(plan, gen))) return 'done';
        continue;
      }
      const { steps } = plan;
      const complete = plan.wantsRanges.length === 0 && !plan.refused;
      // a camera move that leaves the plan as it is on screen: nothing to fetch or compute, and
      // what a superseded step was still fetching is aborted (its chunks are no longer needed)
      if (complete && showsStep(this.#shown, steps[steps.length - 1], iso)) {
        this.fetcher.wantAll([]);
        this.#shown = { ...this.#shown!, cut: plan.cut, final: true };
        return 'done';
      }
      // the finest step already resident: no fetching before it is shown
      let first = 0;
      for (let i = steps.length - 1; i > 0; i--) {
        if (this.#pools.resident(steps[i])) {
          first = i;
          break;
        }
      }
      for (let i = first; i < steps.length; i++) {
        if (stale()) return 'done';
        // on screen already (a plan that goes on once a finer level's range array was read)
        if (showsStep(this.#shown, steps[i], iso)) continue;
        const r = await this.#show(steps[i], plan.cut, iso, gen, complete && i === steps.length - 1);
        if (r === true) continue;
        if (r === false) return 'done';
        // a coarser step than the one on screen that finds no room (the finer one holds it): the finer stays
        const s = this.#shown;
        if (i < steps.length - 1 && s && s.step < steps[i].finest) {
          this.#releaseUnshown();
          continue;
        }
        return { ...r, coarser: plan.coarsenable };
      }
      if (stale()) return 'done';
      if (plan.refused) {
        this.#stop(plan.refused.level, plan.refused.reason, 'limit');
        return 'done';
      }
      if (plan.wantsRanges.length === 0 || !(await this.#readWanted(plan, gen))) return 'done';
    }
  }

  /** The plan at `iso` with the store's levels, ranges, the view and `share` of the budget. */
  #plan(iso: number, share: number): StreamPlan {
    const needs = new Map<number, ((c: ChunkIndex) => boolean) | null>();
    return this.planner.plan({
      iso,
      view: this.#view,
      voxelSize: this.store.voxelSize,
      layouts: this.levels.map((l) => l.layout),
      scales: this.store.levelScales,
      finest: this.finest,
      finestUsable: this.#finestUsable,
      coarsest: this.coarsest,
      unusable: (L) => this.store.levels[L].unusable,
      needs: (L) => {
        if (!needs.has(L)) needs.set(L, this.#pools.needs(L, iso));
        return needs.get(L)!;
      },
      chunkCost: (L) => this.#pools.chunkCost(L),
      // some room for the surfaces being replaced while a step is computed
      budgetBytes: Math.max(0, this.budgetBytes - RESERVE_BYTES) * share,
    });
  }

  /** Reads the range arrays the plan wants; false when that failed (the stream stopped) or went stale. */
  async #readWanted(plan: StreamPlan, gen: number): Promise<boolean> {
    try {
      await Promise.all(plan.wantsRanges.map((L) => this.#pools.readRanges(L)));
    } catch (e) {
      if (gen !== this.#gen || this.#destroyed) return false;
      this.#events.error(e as Error);
      this.#stop(plan.wantsRanges[0], (e as Error).message, 'chunk');
      return false;
    }
    return gen === this.#gen && !this.#destroyed;
  }

  /**
   * Fetches what the step needs, computes its levels' surfaces (finest
   * first), then shows it: true; false when stale or stopped; a BudgetStop
   * when it does not fit (the caller coarsens the cut or stops).
   */
  async #show(step: Step, cut: ViewCut | null, iso: number, gen: number, final: boolean): Promise<boolean | BudgetStop> {
    const stale = () => gen !== this.#gen || this.#destroyed;
    const shownWanted = wantedOnScreen(this.#shown, this.levels.length);
    // pools: room for what the step wants and what is on screen now
    const refused = this.#pools.fitStep(
      step,
      shownWanted,
      () => this.#free(),
      (L) => this.#surfaces.has(L),
      this.budgetBytes,
    );
    if (refused) return refused;
    const { missing, order } = this.#pools.missing(step);
    const total = step.wanted.reduce((a, w) => a + w.length, 0);
    const progress = (phase: StreamProgress['phase']) =>
      this.#events.progress({
        iso,
        level: step.finest,
        chunksDone: total - missing.size,
        chunksNeeded: total,
        bytesFetched: this.fetcher.counters.bytesFetched,
        phase,
      });
    if (missing.size > 0) {
      const keep = step.wanted.map((w, L) => new Set([...w, ...(shownWanted[L] ?? [])].map((c) => key(L, c))));
      let mine: Waiting | null = null;
      await new Promise<void>((resolve) => {
        mine = this.#waiting = { missing, done: resolve, keep };
        this.#pools.reserve(step, missing);
        progress('fetching');
        this.fetcher.wantAll(order);
        if (missing.size === 0) resolve();
      });
      if (this.#waiting === mine) this.#waiting = null;
      if (stale()) return false;
      if (missing.size > 0) return false; // a chunk failed
    } else {
      // everything resident: what a superseded step was still fetching is no longer needed
      this.fetcher.wantAll([]);
    }
    progress('computing');
    const levels: CutLevelShown<V, S, F>[] = [];
    const used = step.levels;
    let computing = step.finest;
    try {
      for (const L of used) {
        computing = L;
        const lv = this.levels[L];
        const pool = lv.volume!;
        // ghosts as skirts: the one cell layer next to a drawn chunk emits too, an overlap into the neighbouring
        // region at another level that covers the crack between the two (counted apart from the cut's triangles)
        pool.setRoles(step.drawn[L], step.ghosts[L], { skirts: this.skirts });
        const noRoom = this.#surfaces.noRoom(L, pool, lv.layout, this.#free(), this.budgetBytes);
        if (noRoom) return { level: L, reason: noRoom };
        const surface = await this.#surfaces.surfaceFor(L, pool, lv.layout, this.#free(), () => stale() || lv.volume !== pool);
        if (!surface) return false;
        surface.setMemoryBudget(Math.max(1, this.budgetBytes - RESERVE_BYTES - (this.gpu.allocatedBytes - surface.budgetedBytes)));
        const stats = await surface.compute(iso);
        if (stale()) return false;
        // what the surface holds, and the copy of it that is drawn (present(), below)
        const drawnCopy = this.snapshots ? (surface.presentBytesNeeded ?? 0) : 0;
        this.#pools.recordCost(L, (stats.cacheBytes + stats.vertexBytes + drawnCopy) / Math.max(1, step.wanted[L].length));
        levels.push({ level: L, volume: pool, surface, stats, drawn: [...step.drawn[L]], ghosts: [...step.ghosts[L]] });
      }
    } catch (e) {
      if (stale()) return false;
      if (isAbort(e) || (e as Error).name === 'IsosurfaceSupersededError') return false;
      if ((e as Error).name === 'IsosurfaceBudgetError') {
        // what the surface needed, per wanted chunk: the cost the next plan uses
        const needed = (e as { neededBytes?: number }).neededBytes;
        if (needed !== undefined && Number.isFinite(needed))
          this.#pools.recordCost(computing, needed / Math.max(1, step.wanted[computing].length), true);
        return { level: computing, reason: (e as Error).message };
      }
      this.#events.error(e as Error);
      this.#stop(step.finest, (e as Error).message, 'gpu');
      return false;
    }
    // A snapshot: the frames until now drew the copies of the step before (whole, whatever was computed in
    // place since); the copies of this step's surfaces are made together now and drawn from here on. Room
    // for them: what they need beyond the copies they replace, less what the surfaces this step lets go held.
    const freed = this.#surfaces.bytesOutside(used);
    const copies = this.snapshots
      ? levels.reduce((a, l) => a + (l.surface.presentBytesNeeded ?? 0) - (l.surface.presentedBytes ?? 0), 0)
      : 0;
    if (this.gpu.allocatedBytes - freed + copies > this.budgetBytes - RESERVE_BYTES / 2) {
      return {
        level: step.finest,
        reason: `the step's surfaces and the copies drawn of them need ${copies} B more than the budget of ${this.budgetBytes} B leaves`,
      };
    }
    // levels this step does not draw: their surfaces go, their pools' chunks become idle
    for (const L of this.#surfaces.letGoOutside(used)) this.levels[L].volume?.setRoles(new Set(), new Set());
    if (this.snapshots) for (const l of levels) l.surface.present?.();
    this.#shown = { iso, step: step.finest, final, levels, cut, leaves: step.leaves };
    // learning is asked for before listeners hear of the step, so their learnSettled() waits for it
    this.#learn(levels);
    this.#events.shown(this.#shown);
    progress('shown');
    return true;
  }

  /**
   * Learns the ranges of the chunks these surfaces read whose range is not
   * known (levels without range arrays), from the block ranges the surfaces
   * were just computed with: valid while no chunk has been put into or
   * evicted from that level's pool since and the surface is still the
   * level's (a finer step fetching meanwhile does not spoil it). Reduced per
   * slot on the GPU, one batch after the other (learnSlotRanges); recorded as
   * they arrive (learnSettled).
   */
  #learn(levels: readonly CutLevelShown<V, S, F>[]): void {
    for (const l of levels) {
      if (this.store.levels[l.level].rangesPath) continue;
      const changes = this.#pools.changes(l.level);
      const valid = () => !this.#destroyed && this.#pools.changes(l.level) === changes && this.#surfaces.get(l.level) === l.surface;
      const chunks = [...l.drawn, ...l.ghosts];
      this.#learning = this.#learning.then(() => learnSlotRanges(this.learnt, l.level, chunks, l.volume, l.surface, valid));
    }
  }

  /** Resolves when the learnt ranges asked for so far are recorded. */
  learnSettled(): Promise<void> {
    return this.#learning;
  }

  /**
   * Lets go of the surfaces and pools of levels that the surface on screen
   * does not draw, and empties the block caches of those that stay (their
   * drawn meshes stay; a cache regrows as its surface needs it).
   */
  #releaseUnshown(): void {
    const shown = (this.#shown?.levels ?? []).map((l) => l.level);
    this.#surfaces.letGoOutside(shown);
    for (const lv of this.levels) if (!shown.includes(lv.index)) this.#pools.dropPool(lv);
    this.#surfaces.trimCaches();
  }

  #free(): number {
    return this.budgetBytes - RESERVE_BYTES - this.gpu.allocatedBytes;
  }

  #arrived(level: number, chunk: ChunkIndex, bytes: Uint8Array): void {
    const w = this.#waiting;
    const lv = this.levels[level];
    if (!w || !lv?.volume || !w.missing.has(key(level, chunk))) return;
    try {
      this.#pools.put(level, chunk, bytes, (c) => w.keep[level]?.has(key(level, c)) ?? false);
    } catch (e) {
      this.#events.error(e as Error);
      this.#stop(level, (e as Error).message, 'chunk');
      return;
    }
    w.missing.delete(key(level, chunk));
    if (w.missing.size === 0) w.done();
  }

  #scheduleRetry(inMs: number): void {
    if (this.#retryTimer !== null) clearTimeout(this.#retryTimer);
    const gen = this.#gen;
    this.#retryTimer = setTimeout(() => {
      this.#retryTimer = null;
      if (gen !== this.#gen || this.#destroyed || !Number.isFinite(this.#iso)) return;
      void this.setIsovalue(this.#iso);
    }, inMs + 50);
  }

  #stop(level: number, reason: string, cause: NonNullable<StreamProgress['cause']>, retryInMs?: number): void {
    const w = this.#waiting;
    this.#waiting = null;
    if (w) {
      this.fetcher.wantAll([]);
      w.done();
    }
    this.#events.stopped(this.#shown?.iso ?? Number.NaN, level, reason, cause, this.fetcher.counters.bytesFetched, retryInMs);
  }

  destroy(): void {
    this.#destroyed = true;
    this.#gen++;
    if (this.#retryTimer !== null) clearTimeout(this.#retryTimer);
    this.fetcher.cancelAll();
    this.#waiting?.done();
    this.#surfaces.destroy();
    this.#pools.destroy();
    this.#shown = null;
  }
}

/** A step that did not fit the budget: the level and why; `coarser` when the cut could be made coarser. */
interface BudgetStop {
  level: number;
  reason: string;
  coarser?: boolean;
}

/** The share of the budget (less the reserve) the cut is planned with: room for surfaces replaced while a step computes. */
const PLAN_SHARE = 0.8;
/** How many times a cut that does not fit is planned again, coarser, before the refinement stops. */
const MAX_COARSENINGS = 6;
/** Kept free within the budget for short-lived buffers (statistics and readback staging, uniforms). */
const RESERVE_BYTES = 1 << 20;
