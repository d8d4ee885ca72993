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
// The budget may be shared (the page's, gpu/budget.ts): a lower limit frees
// at once; a suspended stream holds nothing but the copies it draws.
import type { Clip } from '../../core/clip.ts';
import { GpuBudget } from '../../gpu/budget.ts';
import type { ChunkFetcher } from '../fetch/chunk-fetcher.ts';
import { LearntRanges } from '../learnt-ranges.ts';
import { coarsestDrawableLevel } from '../level-state.ts';
import type { LevelStats, LevelSurface, StreamGpu, StreamGpuBytes, StreamProgress } from '../stream-port.ts';
import { computeStep } from './step-compute.ts';
import { StepFetch } from './step-fetch.ts';
import { StreamMemory } from './stream-memory.ts';
import type { ChunkIndex } from '../types.ts';
import { StreamEvents } from '../stream-events.ts';
import type { ZfpStore } from '../zarr/store.ts';
import type { ViewCut } from '../view/cut.ts';
import { CutPlanner } from './cut-planner.ts';
import type { Planner, StreamPlan } from './planner.ts';
import { StreamLevels } from './stream-levels.ts';
import { StreamSurfaces } from './stream-surfaces.ts';
import {
  type BudgetStop,
  copiesOf,
  type CutLevelShown,
  DEFAULT_TOLERANCE_PX,
  type LevelState,
  type RoleVolume,
  type ShownCut,
  type Step,
  showsStep,
  shownWanted as wantedOnScreen,
  type ViewSpec,
} from './stream-types.ts';

export { type CutLevelShown, DEFAULT_TOLERANCE_PX, type RoleVolume, type ShownCut, type Step, type ViewSpec };

export class StoreStream<V extends RoleVolume, S extends LevelStats, F extends LevelSurface<S>> {
  readonly levels: LevelState<V>[];
  /** Chunk ranges learnt as chunks arrive, for the levels without range arrays (learnt-ranges.ts). */
  readonly learnt: LearntRanges;
  /** Per level: ranges, pool, resident chunks, which chunks a surface needs, the cost model (stream-levels.ts). */
  readonly #pools: StreamLevels<V>;
  /** The GPU memory everything here is held against (shared with the page's other users of it). */
  readonly budget: GpuBudget;
  finest = 0;
  coarsest: number;
  /** The finest level the cut may use: levels below it, or one between, cannot be drawn. */
  #finestUsable = 0;
  #view: ViewSpec | null = null;
  /** Where an image's rays found the surface, per level-0 chunk (a cut for rays; setSeen), or null. */
  #seen: Uint32Array | null = null;
  #iso = Number.NaN;
  /** Other isovalues drawn with #iso from the same resident chunks (several surfaces). */
  #others: readonly number[] = [];
  #gen = 0;
  #destroyed = false;
  /** Stopped and holding only the copies it draws (the page opens another store); a new isovalue resumes it. */
  #suspended = false;
  /** Readers of the step on screen (exports): a new step is not shown before they are done. */
  #holds: Promise<unknown>[] = [];
  #shown: ShownCut<V, S, F> | null = null;
  /**
   * The block caches changed since the step on screen was computed: another
   * step's surfaces were computed on them (shown or not), or they were
   * emptied to give memory back. Its copies stay drawn either way.
   */
  #cachesChanged = false;
  #keepCaches = false;
  readonly #surfaces: StreamSurfaces<V, S, F>;
  /** Pools and surfaces against the budget: room, giving back, figures. */
  readonly #memory: StreamMemory<V, S, F>;
  /** Unsubscribes from the fetcher and the budget. */
  readonly #unlisten: (() => void)[] = [];
  /** The chunks the step being shown waits for. */
  readonly #fetch: StepFetch<V>;
  /** A refinement stopped by a failed chunk is tried again when the chunk has cooled down. */
  #retryTimer: ReturnType<typeof setTimeout> | null = null;
  /** Ghosts as skirts (ChunkedVolume's 'skirt' role): level seams covered by a one-cell overlap. */
  skirts = true;
  /** Whether failed chunks are tried again on their own (the page; the CLI reports the failure instead). */
  retryFailed = true;
  /**
   * Starts a refinement the stream wants on its own at its isovalue (a
   * failed chunk cooled down, a new budget, the caches read again): the
   * page routes it through its own bookkeeping (`done`, the line) by
   * calling setIsovalue; null: the stream calls it itself.
   */
  refineAgain: (() => void) | null = null;
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
    budget: GpuBudget,
    /** What the steps draw: by view (view/cut-planner.ts) or level by level (level-planner.ts). */
    readonly planner: Planner,
    learnt?: LearntRanges,
  ) {
    this.budget = budget;
    this.#unlisten.push(budget.onChange((next, previous) => this.#budgetChanged(next, previous)));
    // ranges learnt earlier in the session (the same store reopened at the same rate) carry over
    const grids = store.levels.map((l) => l.layout.chunkGrid);
    this.learnt = learnt?.fits(grids) ? learnt : new LearntRanges(grids);
    this.#pools = new StreamLevels(store, gpu, this.learnt);
    this.levels = this.#pools.levels;
    this.#surfaces = new StreamSurfaces(gpu);
    this.#memory = new StreamMemory(budget, gpu, this.#pools, this.#surfaces);
    this.#fetch = new StepFetch(fetcher, this.#pools, (level, e) => {
      this.#events.error(e);
      this.#stop(level, e.message, 'chunk');
    });
    this.coarsest = coarsestDrawableLevel(store.levels);
    // levels finer than a level that cannot be drawn (wider than a surface can be) are never split into:
    // the cut stops there (the store's notes say which levels cannot be shown)
    this.#finestUsable = this.coarsest;
    while (this.#finestUsable > 0 && !store.levels[this.#finestUsable - 1].unusable) this.#finestUsable--;
    this.#unlisten.push(fetcher.onChunk((level, chunk, bytes) => this.#fetch.arrived(level, chunk, bytes)));
    this.#unlisten.push(
      fetcher.onError((level, chunk, e, repeated) => {
        if (!repeated) this.#events.error(e);
        if (!this.#fetch.waitsFor(level, chunk)) return;
        const at = fetcher.retryAt(level, chunk);
        const inMs = at === undefined ? undefined : Math.max(0, at - performance.now());
        this.#stop(level, e.message, 'chunk', inMs);
        // the coarser surface stays; once the chunk has cooled down, the same isovalue and view again
        if (inMs !== undefined && this.retryFailed) this.#scheduleRetry(inMs);
      }),
    );
  }

  /**
   * A stream planned by `planner`, once the coarsest level's range array is
   * read. `budget`: a shared GpuBudget, or bytes for a budget of its own
   * (what its port holds against it).
   */
  static async create<V extends RoleVolume, S extends LevelStats, F extends LevelSurface<S>>(
    store: ZfpStore,
    fetcher: ChunkFetcher,
    gpu: StreamGpu<V, S, F>,
    budget: GpuBudget | number,
    planner: Planner,
    options: { learnt?: LearntRanges } = {},
  ): Promise<StoreStream<V, S, F>> {
    const shared = typeof budget === 'number' ? new GpuBudget(budget, undefined, () => gpu.allocatedBytes) : budget;
    const v = new StoreStream(store, fetcher, gpu, shared, planner, options.learnt);
    try {
      await v.#pools.readRanges(v.coarsest);
    } catch (e) {
      v.destroy();
      throw e;
    }
    return v;
  }

  /** A stream refined by the view (setView before setIsovalue). */
  static byView<V extends RoleVolume, S extends LevelStats, F extends LevelSurface<S>>(
    store: ZfpStore,
    fetcher: ChunkFetcher,
    gpu: StreamGpu<V, S, F>,
    budget: GpuBudget | number,
    options: { learnt?: LearntRanges } = {},
  ): Promise<StoreStream<V, S, F>> {
    return StoreStream.create(store, fetcher, gpu, budget, new CutPlanner(), options);
  }

  /** The budget's limit, bytes (set it on `budget`: everyone holding against it is told). */
  get budgetBytes(): number {
    return this.budget.bytes;
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

  /**
   * Whether the live block caches of the step on screen hold what it was
   * computed from (every block active at its isovalue): not while a step's
   * surfaces are computed (the caches change on the GPU), nor once they
   * were emptied to give memory back or the step was released to its
   * copies. The ray caster reads them only then; the copies stay whole.
   */
  get cachesShown(): boolean {
    return !this.#cachesChanged && this.#shown !== null && !this.#shown.frozen;
  }

  /**
   * Whether something reads the live block caches of the step on screen
   * (the page's ray caster): then a step on screen whose caches changed
   * since (a superseded step computed on them, or they were emptied) is
   * computed again rather than taken as shown, and turning this on asks
   * for it at once. Off: the copies are all that is drawn.
   */
  setKeepCaches(on: boolean): void {
    if (on === this.#keepCaches) return;
    this.#keepCaches = on;
    if (on && this.#cachesChanged && !this.#suspended && !this.#destroyed && Number.isFinite(this.#iso)) this.#again();
  }

  get shown(): ShownCut<V, S, F> | null {
    return this.#shown;
  }

  /** GPU bytes this stream holds now (counted where they are made): pools, surfaces, and of these the cache and vertex buffers. */
  get gpuBytes(): StreamGpuBytes {
    return this.#memory.bytes(this.#shown);
  }

  /** [min, max] per chunk of a level, when known for every chunk (its range array, or every chunk's learnt as chunks arrived). */
  chunkRanges(level: number): Float32Array | null {
    return this.#pools.knownRanges(level);
  }

  /** [min, max] of the store's values: its metadata, else the finest level whose chunk ranges are (partly) known. */
  get valueRange(): [number, number] | null {
    return this.#pools.valueRange;
  }

  /** Whether suspend() stopped it (a new isovalue resumes it). */
  get suspended(): boolean {
    return this.#suspended;
  }

  /** Cuts the surfaces open from the next plan on (setIsovalue): chunks the clip removes whole are left out (the renderer clips the rest). */
  setClip(clip: Clip | undefined): void {
    this.#pools.clip = clip;
  }

  get clip(): Clip | undefined {
    return this.#pools.clip;
  }

  /** Whether the clip's caps are drawn: from the next plan on, the chunks they read are needed too (StreamLevels.capNeeds). */
  setCaps(on: boolean): void {
    this.#pools.caps = on;
  }

  get caps(): boolean {
    return this.#pools.caps;
  }

  /** Chunks a surface needed by their ranges that the clip left out, so far. */
  get clippedChunks(): number {
    return this.#pools.clipped.size;
  }

  /** A new camera (or tolerance): the cut is planned again at the current isovalue; resolves when that refinement ends. */
  setView(view: ViewSpec): Promise<void> {
    this.#view = view;
    // what the rays saw was seen from the old camera
    this.#seen = null;
    return Number.isFinite(this.#iso) ? this.setIsovalue(this.#iso) : Promise.resolve();
  }

  /** What the rays saw since the last camera or isovalue (setSeen), or null. */
  get seen(): Uint32Array | null {
    return this.#seen;
  }

  /**
   * Where an image's rays found the surface (per level-0 chunk, x fastest: 1
   * where a first hit lay; null: none): the cut is planned again for rays at
   * the current isovalue and view (CutInput.seen: finer chunks only there,
   * nested over coarser ones), until the next camera or isovalue; resolves
   * when that refinement ends. Only for a stream whose steps the rays draw
   * (a nested cut's meshes overlap where a coarse chunk is drawn under finer ones).
   */

  setSeen(seen: Uint32Array | null): Promise<void> {
    this.#seen = seen;
    return Number.isFinite(this.#iso) ? this.setIsovalue(this.#iso) : Promise.resolve();
  }

  /** The other isovalues each step draws besides the current one (several surfaces). */
  get otherIsovalues(): readonly number[] {
    return this.#others;
  }

  /**
   * Newest wins: resolves when this isovalue's refinement (for the current
   * view) ends: the whole plan shown, stopped, or superseded. `others`: the
   * isovalues drawn with it (several surfaces; default: those of the last
   * call): every step draws them all from the same resident chunks, and a
   * chunk is needed when any of them needs it.
   */
  async setIsovalue(iso: number, others: readonly number[] = this.#others): Promise<void> {
    if (this.#destroyed) return;
    this.#suspended = false;
    const gen = ++this.#gen;
    // what the rays saw was the surface of another isovalue
    if (iso !== this.#iso) this.#seen = null;
    this.#iso = iso;
    this.#others = others.filter((o, i) => o !== iso && others.indexOf(o) === i);
    this.#fetch.supersede();
    if (!this.#view && this.planner.needsView) throw new Error('StoreStream: setView before setIsovalue');
    // A step that does not fit (a pool that cannot grow, a surface over its cap) is tried once more with
    // what is not on screen let go, then made coarser: planned again with what the surfaces really took
    // (the cost model) and less of the budget each time; the coarser step stays on screen meanwhile.
    let share = PLAN_SHARE;
    for (let attempt = 0; ; attempt++) {
      const r = await this.#refine(iso, this.#others, gen, share);
      if (r === 'done' || gen !== this.#gen || this.#destroyed) return;
      // what the step that did not fit made goes; what is on screen stays
      this.#releaseUnshown();
      if ((r.coarser || attempt === 0) && attempt < MAX_COARSENINGS) {
        if (r.coarser) share *= 0.85;
        continue;
      }
      await this.#restoreShown(gen);
      this.#stop(r.level, r.reason, 'budget');
      return;
    }
  }

  /** Plans with `share` of the budget and shows the plan's steps; 'done', or a step that did not fit. */
  async #refine(iso: number, others: readonly number[], gen: number, share: number): Promise<'done' | BudgetStop> {
    const stale = () => gen !== this.#gen || this.#destroyed;
    let relearnt = 0;
    for (;;) {
      // what a wanted chunk of each level cost when this plan was made (the cost model learns as surfaces are made)
      const plannedCosts = this.levels.map((_, L) => this.#pools.chunkCost(L));
      const plan = this.#plan([iso, ...others], share);
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
      if (complete && this.#showsWhole(steps[steps.length - 1], iso, others)) {
        this.fetcher.wantAll([]);
        const wasFinal = this.#shown!.final;
        this.#shown = { ...this.#shown!, cut: plan.cut, final: true };
        // a coarser plan whose last step is the one on screen (shown as a step on the way, not final): it is
        // the end of this refinement now, and listeners hear so (the page's progress, the rays' guidance)
        if (!wasFinal) {
          this.#events.shown(this.#shown);
          const chunks = steps[steps.length - 1].wanted.reduce((a, w) => a + w.length, 0);
          this.#events.progress({
            iso,
            level: this.#shown.step,
            chunksDone: chunks,
            chunksNeeded: chunks,
            bytesFetched: this.fetcher.counters.bytesFetched,
            phase: 'shown',
          });
        }
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
        if (this.#showsWhole(steps[i], iso, others)) continue;
        const r = await this.#show(steps[i], plan.cut, iso, others, gen, complete && i === steps.length - 1);
        if (r === true) continue;
        if (r === false) return 'done';
        // a coarser step than the one on screen that finds no room (the finer one holds it): the finer stays
        const s = this.#shown;
        if (i < steps.length - 1 && s && !s.frozen && s.step < steps[i].finest) {
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
      // A cut the budget held back, planned with costs its surfaces turned out to be well under (a first
      // guess; a cache-only surface's few active blocks): planned again with what they took, so the
      // budget left over goes to finer chunks where the view wants them.
      if (complete && relearnt < MAX_RELEARNS && plan.cut?.limitedByBudget && this.#overestimated(plan, plannedCosts)) {
        relearnt++;
        continue;
      }
      if (plan.wantsRanges.length === 0 || !(await this.#readWanted(plan, gen))) return 'done';
    }
  }

  /** Whether some level the plan draws now costs well under what the plan counted per wanted chunk. */
  #overestimated(plan: StreamPlan, plannedCosts: readonly number[]): boolean {
    const last = plan.steps[plan.steps.length - 1];
    return last.wanted.some((w, L) => w.length > 0 && this.#pools.chunkCost(L) < RELEARN_RATIO * plannedCosts[L]);
  }

  /**
   * The chunks another time point of this store would want now, most urgent
   * first (its plan's steps coarse to fine, each chunk once): the plan this
   * stream makes at its isovalues and view, with `needsAt(L, iso)` (that
   * time point's ranges) saying which chunks hold surface; a level whose
   * needs are unknown (null) counts every chunk. Null before an isovalue
   * (or, planned by the view, a view). What a series prefetches
   * (../series/prefetch.ts): the next time point's session makes the same
   * plan unless the surface moved far.
   */
  wantedAhead(needsAt: (L: number, iso: number) => ((c: ChunkIndex) => boolean) | null): { level: number; chunk: ChunkIndex }[] | null {
    if (this.#destroyed || !Number.isFinite(this.#iso) || (!this.#view && this.planner.needsView)) return null;
    const plan = this.#plan([this.#iso, ...this.#others], PLAN_SHARE, (L, iso) => {
      const byRange = needsAt(L, iso) ?? (() => true);
      // the clip leaves out the same chunks at every time point
      return (c) => byRange(c) && !this.#pools.clippedAway(L, c);
    });
    const seen = new Set<number>();
    const out: { level: number; chunk: ChunkIndex }[] = [];
    for (const step of plan.steps)
      for (let L = step.wanted.length - 1; L >= 0; L--)
        for (const chunk of step.wanted[L]) {
          const k = L * 2 ** 32 + chunk;
          if (seen.has(k)) continue;
          seen.add(k);
          out.push({ level: L, chunk });
        }
    return out;
  }

  /**
   * The plan at `isos` (a chunk is needed when any needs it) with the store's levels, ranges (or those
   * `needsOf` gives), the view and `share` of the budget.
   */
  #plan(
    isos: readonly number[],
    share: number,
    needsOf: (L: number, iso: number) => ((c: ChunkIndex) => boolean) | null = (L, iso) => this.#pools.needs(L, iso),
  ): StreamPlan {
    const needs = new Map<number, ((c: ChunkIndex) => boolean) | null>();
    // the caps read the chunks along the cut where the values reach the outermost surface's isovalue
    const threshold = Math.min(...isos);
    const anyNeeds = (L: number) => {
      const each = isos.map((iso) => needsOf(L, iso));
      if (each.some((n) => n === null)) return null;
      const caps = this.#pools.capNeeds(L, threshold);
      if (caps) each.push(caps);
      return each.length === 1 ? each[0] : (c: ChunkIndex) => each.some((n) => n!(c));
    };
    return this.planner.plan({
      iso: isos[0],
      view: this.#view,
      voxelSize: this.store.voxelSize,
      layouts: this.levels.map((l) => l.layout),
      scales: this.store.levelScales,
      finest: this.finest,
      finestUsable: this.#finestUsable,
      coarsest: this.coarsest,
      unusable: (L) => this.store.levels[L].unusable,
      needs: (L) => {
        if (!needs.has(L)) needs.set(L, anyNeeds(L));
        return needs.get(L)!;
      },
      chunkCost: (L) => this.#pools.chunkCost(L),
      // some room for the surfaces being replaced while a step is computed; what others hold against the
      // budget (the page's store being replaced) and the copies this stream's next step replaces are not for it
      budgetBytes: this.#memory.planBytes(share),
      seen: this.#seen,
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
  async #show(
    step: Step,
    cut: ViewCut | null,
    iso: number,
    others: readonly number[],
    gen: number,
    final: boolean,
  ): Promise<boolean | BudgetStop> {
    const stale = () => gen !== this.#gen || this.#destroyed;
    const shownWanted = wantedOnScreen(this.#shown, this.levels.length);
    // pools: room for what the step wants and what is on screen now
    const refused = this.#pools.fitStep(
      step,
      shownWanted,
      () => this.#memory.free(),
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
    const arrived = await this.#fetch.fetch(step, missing, order, shownWanted, () => progress('fetching'));
    if (stale() || !arrived) return false; // superseded, or a chunk failed
    progress('computing');
    this.#cachesChanged = true;
    const computed = await computeStep(
      step,
      iso,
      others,
      {
        pools: this.#pools,
        surfaces: this.#surfaces,
        memory: this.#memory,
        skirts: this.skirts,
        snapshots: this.snapshots,
        previous: this.#shown,
      },
      stale,
    );
    if ('stale' in computed) return false;
    if ('stop' in computed) return computed.stop;
    if ('error' in computed) {
      this.#events.error(computed.error);
      this.#stop(computed.level, computed.error.message, 'gpu');
      return false;
    }
    const { levels } = computed;
    const used = step.levels;
    // the other surfaces' copies this step made (not those it keeps from the step on screen) go if it is not shown
    const dropNew = () => {
      const keep = copiesOf(this.#shown);
      for (const c of copiesOf({ levels })) if (!keep.has(c)) c.destroy();
    };
    // A snapshot: the frames until now drew the copies of the step before (whole, whatever was computed in
    // place since); the copies of this step's surfaces are made together now and drawn from here on.
    const noCopies = this.snapshots ? this.#memory.copiesRefusal(used, levels) : null;
    if (noCopies) {
      dropNew();
      return { level: step.finest, reason: noCopies };
    }
    // readers of the step on screen (an export) finish before it is replaced
    while (this.#holds.length > 0) {
      await Promise.allSettled(this.#holds);
      if (stale()) {
        dropNew();
        return false;
      }
    }
    // levels this step does not draw: their surfaces go, their pools' chunks become idle
    for (const L of this.#surfaces.letGoOutside(used)) this.levels[L].volume?.setRoles(new Set(), new Set());
    if (this.snapshots) for (const l of levels) l.surface.present?.();
    const before = this.#shown;
    this.#shown = { iso, others: [...others], step: step.finest, final, levels, cut, leaves: step.leaves };
    this.#cachesChanged = false;
    this.#dropCopiesOf(before);
    // learning is asked for before listeners hear of the step, so their learnSettled() waits for it
    this.#pools.learn(levels, (l) => !this.#destroyed && !this.#suspended && this.#surfaces.get(l.level) === l.surface);
    this.#events.shown(this.#shown);
    progress('shown');
    return true;
  }

  /** Resolves when the learnt ranges asked for so far are recorded. */
  learnSettled(): Promise<void> {
    return this.#pools.learnSettled();
  }

  /** Whether the step on screen is `step` at these isovalues, with its live caches too when they are read (setKeepCaches). */
  #showsWhole(step: Step, iso: number, others: readonly number[]): boolean {
    return showsStep(this.#shown, step, iso, others) && !(this.#keepCaches && this.#cachesChanged);
  }

  /**
   * Reads the step on screen with `read` (an export, from its drawn copies):
   * no new step is shown before it is done. Null when nothing is on screen.
   */
  async readShown<T>(read: (shown: ShownCut<V, S, F>) => Promise<T>): Promise<T | null> {
    const shown = this.#shown;
    if (!shown || this.#destroyed) return null;
    const reading = read(shown);
    this.#holds.push(reading);
    try {
      return await reading;
    } finally {
      this.#holds = this.#holds.filter((h) => h !== reading);
    }
  }

  /**
   * Stops (no fetches, decodes, timers or learning go on) and lets go of
   * everything but the copies the step on screen is drawn from: the page
   * opens another store within the same budget while this one stays on
   * screen. A new isovalue (setIsovalue) resumes it.
   */
  suspend(): void {
    if (this.#destroyed) return;
    this.#suspended = true;
    this.#interrupt();
    this.#releaseUnshown();
    this.#releaseToCopies();
  }

  /**
   * The limit changed. Lower: within it at once: what the step on screen
   * does not draw goes, then (still over) all but its drawn copies, then the
   * copies (nothing drawn until the next step). Either way the refinement is
   * planned again (a microtask later; a suspended stream waits to be resumed).
   */
  #budgetChanged(next: number, previous: number): void {
    if (this.#destroyed) return;
    if (next < previous && this.#memory.over) {
      this.#interrupt();
      this.#releaseUnshown();
      if (this.#memory.over) this.#releaseToCopies();
      // the copies alone are over: listeners hear that nothing is drawn until the next step
      if (this.#memory.over && this.#shown && this.#shown.levels.length > 0) {
        const before = this.#shown;
        this.#shown = this.#memory.releaseAll(this.#shown);
        this.#dropCopiesOf(before);
        if (this.#shown) this.#events.shown(this.#shown);
      }
    }
    // planned again for the new limit, unless someone asks for an isovalue first (the page, after every listener shed)
    const gen = this.#gen;
    queueMicrotask(() => {
      if (gen === this.#gen && !this.#destroyed && !this.#suspended && Number.isFinite(this.#iso)) this.#again();
    });
  }

  /** The other surfaces' copies a step held that the step on screen does not (it replaced that step). */
  #dropCopiesOf(replaced: ShownCut<V, S, F> | null): void {
    const keep = copiesOf(this.#shown);
    for (const c of copiesOf(replaced)) if (!keep.has(c)) c.destroy();
  }

  /** Whatever is being fetched or computed is no longer wanted (it becomes stale). */
  #interrupt(): void {
    this.#gen++;
    if (this.#retryTimer !== null) clearTimeout(this.#retryTimer);
    this.#retryTimer = null;
    this.#fetch.end();
  }

  /** Lets go of what the step on screen does not draw (StreamMemory.releaseUnshown). */
  #releaseUnshown(): void {
    this.#memory.releaseUnshown(this.#shown);
    this.#cachesChanged = true;
  }

  /** Keeps only the copies the step on screen is drawn from (without copies, the CLI's, only what is not on screen goes). */
  #releaseToCopies(): void {
    if (this.snapshots) this.#shown = this.#memory.releaseToCopies(this.#shown);
  }

  #scheduleRetry(inMs: number): void {
    if (this.#retryTimer !== null) clearTimeout(this.#retryTimer);
    const gen = this.#gen;
    this.#retryTimer = setTimeout(() => {
      this.#retryTimer = null;
      if (gen !== this.#gen || this.#destroyed || this.#suspended || !Number.isFinite(this.#iso)) return;
      this.#again();
    }, inMs + 50);
  }

  /**
   * When the live caches are read (setKeepCaches: the rays) and a step that
   * did not fit computed on them, the step on screen is computed again from
   * its chunks, still resident, so what the rays read is what it shows.
   */
  async #restoreShown(gen: number): Promise<void> {
    const shown = this.#shown;
    if (!this.#keepCaches || !this.#cachesChanged || !shown || shown.frozen || gen !== this.#gen || this.#destroyed) return;
    const n = this.levels.length;
    const drawn = Array.from({ length: n }, () => new Set<ChunkIndex>());
    const ghosts = Array.from({ length: n }, () => new Set<ChunkIndex>());
    for (const l of shown.levels) {
      for (const c of l.drawn) drawn[l.level].add(c);
      for (const c of l.ghosts) ghosts[l.level].add(c);
    }
    const step: Step = {
      finest: shown.step,
      levels: shown.levels.map((l) => l.level),
      leaves: shown.leaves.map((l) => [...l]),
      drawn,
      ghosts,
      wanted: drawn.map((d, L) => [...d, ...ghosts[L]]),
    };
    await this.#show(step, shown.cut, shown.iso, shown.others, gen, shown.final);
  }

  /** A refinement at the current isovalue the stream wants on its own (refineAgain). */
  #again(): void {
    if (this.refineAgain) this.refineAgain();
    else void this.setIsovalue(this.#iso);
  }

  #stop(level: number, reason: string, cause: NonNullable<StreamProgress['cause']>, retryInMs?: number): void {
    this.#fetch.end();
    this.#events.stopped(this.#shown?.iso ?? Number.NaN, level, reason, cause, this.fetcher.counters.bytesFetched, retryInMs);
  }

  destroy(): void {
    if (this.#destroyed) return;
    this.#destroyed = true;
    for (const u of this.#unlisten) u();
    this.#gen++;
    if (this.#retryTimer !== null) clearTimeout(this.#retryTimer);
    this.#retryTimer = null;
    this.#fetch.end();
    this.#surfaces.destroy();
    this.#pools.destroy();
    const before = this.#shown;
    this.#shown = null;
    this.#dropCopiesOf(before);
  }
}

/** The share of the budget (less the reserve) the cut is planned with: room for surfaces replaced while a step computes. */
const PLAN_SHARE = 0.8;
/** How many times a cut held back by the budget is planned again with the costs its surfaces taught (`#overestimated`). */
const MAX_RELEARNS = 2;
/** A level's cost per wanted chunk under this fraction of what a plan counted makes that plan worth making again. */
const RELEARN_RATIO = 0.8;
/** How many times a cut that does not fit is planned again, coarser, before the refinement stops. */
const MAX_COARSENINGS = 6;
