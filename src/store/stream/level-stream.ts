// A store streamed level by level, as the CLI's `--level L` and the page's
// level-by-level mode read it: the one store stream (store-stream.ts)
// planned by LevelPlanner, shown as one level's surface at a time (the
// coarsest first, then each finer level that replaces it), with the value
// range and chunk ranges of the finest level known.
import type { GpuBudget } from '../../gpu/budget.ts';
import type { ChunkFetcher } from '../fetch/chunk-fetcher.ts';
import type { LearntRanges } from '../learnt-ranges.ts';
import type { LevelStats, LevelSurface, ShownSurface, StreamGpu, StreamGpuBytes, StreamProgress } from '../stream-port.ts';
import type { ZfpStore } from '../zarr/store.ts';
import { LevelPlanner } from './level-planner.ts';
import { StoreStream } from './store-stream.ts';
import type { LevelState, RoleVolume, ShownCut } from './stream-types.ts';

export class LevelStream<V extends RoleVolume, S extends LevelStats, F extends LevelSurface<S>> {
  private constructor(
    /** The stream itself (the same engine as a view's). */
    readonly stream: StoreStream<V, S, F>,
    readonly planner: LevelPlanner,
  ) {}

  static async create<V extends RoleVolume, S extends LevelStats, F extends LevelSurface<S>>(
    store: ZfpStore,
    fetcher: ChunkFetcher,
    gpu: StreamGpu<V, S, F>,
    budget: GpuBudget | number,
    options: { learnt?: LearntRanges } = {},
  ): Promise<LevelStream<V, S, F>> {
    const planner = new LevelPlanner(store.levels[0].layout);
    const stream = await StoreStream.create(store, fetcher, gpu, budget, planner, options);
    // read once the refinement ended (the CLI, tests): each level is whole when it shows, no copies needed
    stream.snapshots = false;
    return new LevelStream(stream, planner);
  }

  get store(): ZfpStore {
    return this.stream.store;
  }
  get fetcher(): ChunkFetcher {
    return this.stream.fetcher;
  }
  get levels(): readonly LevelState<V>[] {
    return this.stream.levels;
  }
  get learnt(): LearntRanges {
    return this.stream.learnt;
  }
  get gpuBytes(): StreamGpuBytes {
    return this.stream.gpuBytes;
  }
  /** The whole stream's GPU memory (set it on `stream.budget`). */
  get budgetBytes(): number {
    return this.stream.budgetBytes;
  }
  /** The levels refinement may use: from `coarsest` down to `finest` (a link's #level=, the CLI's --level L with both at L). */
  get finest(): number {
    return this.stream.finest;
  }
  set finest(L: number) {
    this.stream.finest = L;
  }
  get coarsest(): number {
    return this.stream.coarsest;
  }
  set coarsest(L: number) {
    this.stream.coarsest = L;
  }
  /** Where "nearest first" measures from, in level-0 voxels (default: the volume's centre). */
  get focus(): [number, number, number] {
    return this.planner.focus;
  }
  set focus(p: [number, number, number]) {
    this.planner.focus = p;
  }

  /** The level on screen. */
  get shown(): ShownSurface<V, S, F> | null {
    return levelOf(this.stream.shown);
  }

  onProgress(l: (p: StreamProgress) => void): () => void {
    return this.stream.onProgress(l);
  }
  onShown(l: (s: ShownSurface<V, S, F>) => void): () => void {
    return this.stream.onShown((s) => {
      const shown = levelOf(s);
      if (shown) l(shown);
    });
  }
  /** Chunk failures (each once, not its repeats during the cool-down) and GPU errors. */
  onError(l: (e: Error) => void): () => void {
    return this.stream.onError(l);
  }

  /**
   * Newest wins: resolves when this isovalue's refinement ends (finest level
   * reached, stopped, or superseded) and the chunk ranges its surfaces read
   * are learnt (the next isovalue plans with them).
   */
  async setIsovalue(iso: number): Promise<void> {
    await this.stream.setIsovalue(iso);
    await this.stream.learnSettled();
  }

  /** [min, max] per chunk of a level, when known for every chunk (range arrays, or every chunk's learnt). */
  chunkRanges(level: number): Float32Array | null {
    return this.stream.chunkRanges(level);
  }

  /** The store's value range: its metadata, else the finest level whose chunk ranges are (partly) known; null when none is. */
  get valueRange(): [number, number] | null {
    return this.stream.valueRange;
  }

  destroy(): void {
    this.stream.destroy();
  }
}

/** A level-by-level step on screen as its one level. */
function levelOf<V, S extends LevelStats, F extends LevelSurface<S>>(s: ShownCut<V, S, F> | null): ShownSurface<V, S, F> | null {
  const l = s?.levels[0];
  return s && l ? { level: l.level, iso: s.iso, volume: l.volume, surface: l.surface, stats: l.stats } : null;
}
