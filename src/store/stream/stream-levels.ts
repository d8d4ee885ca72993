// The store stream's per-level state (store-stream.ts): each level's chunk
// ranges (range arrays, read when first needed, or ranges learnt as chunks
// arrive), its pool of compressed chunks on the GPU with the resident chunks
// least recently wanted first, which chunks a surface needs, and what a
// wanted chunk costs on the GPU (the plan's cost model).
import { type LearntRanges, learnSlotRanges } from '../learnt-ranges.ts';
import {
  chunkCount,
  estimateFixedBytes,
  guessedSurfaceBytesPerChunk,
  putArrived,
  readLevelRanges,
  residentChunkBytes,
  storeValueRange,
} from '../level-state.ts';
import { type Clip, clipIsEmpty, regionClipped, regionOnCap } from '../../core/clip.ts';
import { chunkNeeded } from '../plan.ts';
import type { LevelSurface, StreamGpu } from '../stream-port.ts';
import type { ChunkIndex } from '../types.ts';
import type { ZfpStore } from '../zarr/store.ts';
import { key, type LevelState, type RoleVolume, type Step } from './stream-types.ts';

export class StreamLevels<V extends RoleVolume> {
  readonly levels: LevelState<V>[];
  /** Per level, chunks put into or evicted from its pool so far: a surface's block ranges are its slots' chunks' while this is unchanged. */
  readonly #changes: number[];
  /** Levels whose range array was read (it may have held none: every chunk is then needed). */
  readonly #read = new Set<number>();
  /** Per level, the cache and vertex bytes its last surface took (or needed, when it did not fit) per wanted chunk. */
  readonly #surfaceCost: (number | undefined)[] = [];
  /** The readbacks of learnt ranges in flight (learnSettled). */
  #learning: Promise<void> = Promise.resolve();
  /** Cuts the surfaces open (level-0 voxels): a chunk whose cells it removes whole is never needed. */
  clip: Clip | undefined;
  /** Chunks (level, index) a surface needed by their ranges that the clip left out. */
  readonly clipped = new Set<number>();
  /** Whether the clip's caps are drawn: the chunks they read are needed too (capNeeds). */
  caps = false;

  constructor(
    readonly store: ZfpStore,
    readonly gpu: Pick<StreamGpu<V>, 'createVolume' | 'poolBytesFor' | 'cacheOnly'>,
    readonly learnt: LearntRanges,
  ) {
    this.#changes = store.levels.map(() => 0);
    this.levels = store.levels.map((l, i) => ({
      index: i,
      layout: l.layout,
      ranges: null,
      nb: null,
      reading: null,
      volume: null,
      lru: new Map(),
    }));
  }

  /** The level's range array, read once (a failed read is tried again next time; rejects with its StoreError). */
  readRanges(L: number): Promise<void> {
    return readLevelRanges(this.store, this.levels[L]).then(() => {
      this.#read.add(L);
    });
  }

  /** Which chunks of level L the surface at `iso` needs, or null while its range array is unread. */
  needs(L: number, iso: number): ((c: ChunkIndex) => boolean) | null {
    const byRange = this.#needsByRange(L, iso);
    const clip = this.clip;
    if (!byRange || clipIsEmpty(clip)) return byRange;
    return (c) => {
      if (!byRange(c)) return false;
      if (!this.#clippedAway(L, c, clip!)) return true;
      this.clipped.add(key(L, c));
      return false;
    };
  }

  /**
   * The chunks of level L the clip's caps read (none without caps or a
   * clip): a clip plane passes through their cells and the clip keeps part
   * of them, where their neighbourhood's values reach `threshold` (a cap is
   * drawn where the value is at least the outermost surface's isovalue; any
   * chunk while its ranges are unknown).
   */
  capNeeds(L: number, threshold: number): ((c: ChunkIndex) => boolean) | null {
    const clip = this.clip;
    if (!this.caps || clipIsEmpty(clip) || this.store.levels[L].unusable) return null;
    const nb = this.levels[L].nb;
    return (c) => {
      if (nb && !(nb[2 * c + 1] >= threshold)) return false;
      const { lo, hi } = this.#chunkRegion(L, c);
      return regionOnCap(lo, hi, clip);
    };
  }

  /** Chunk c of level L in level-0 voxels: its voxels and the next chunk's first (the cells it holds), one of its voxels of slack. */
  #chunkRegion(L: number, c: ChunkIndex): { lo: number[]; hi: number[] } {
    const { chunkGrid, chunkEdge } = this.levels[L].layout;
    const scale = this.store.levelScales[L];
    const offset = this.store.levelOffsets[L] ?? [0, 0, 0];
    const at = [c % chunkGrid[0], Math.floor(c / chunkGrid[0]) % chunkGrid[1], Math.floor(c / (chunkGrid[0] * chunkGrid[1]))];
    return {
      lo: at.map((g, a) => offset[a] + (g * chunkEdge - 1) * scale[a]),
      hi: at.map((g, a) => offset[a] + ((g + 1) * chunkEdge + 1) * scale[a]),
    };
  }

  /** Whether the clip removes every cell of chunk c of level L (its voxels and the next chunk's first, in level-0 voxels, one of its voxels of slack). */
  /** Whether the clip removes chunk c of level L whole (nothing counted: the plan ahead of a series uses it). */
  clippedAway(L: number, c: ChunkIndex): boolean {
    const clip = this.clip;
    return !clipIsEmpty(clip) && this.#clippedAway(L, c, clip!);
  }

  #clippedAway(L: number, c: ChunkIndex, clip: Clip): boolean {
    const { lo, hi } = this.#chunkRegion(L, c);
    return regionClipped(lo, hi, clip);
  }

  #needsByRange(L: number, iso: number): ((c: ChunkIndex) => boolean) | null {
    const lv = this.levels[L];
    if (this.store.levels[L].unusable) return null;
    // read from the neighbourhood ranges per chunk asked: nothing made per level (a level may have 2^24 chunks)
    const nb = lv.nb;
    if (nb) return (c) => chunkNeeded(nb, iso, c);
    // no range arrays: the ranges learnt so far, every chunk with an unknown neighbour may hold the surface
    if (!this.store.levels[L].rangesPath) return this.learnt.learns(L) ? (c) => this.learnt.needs(L, iso, c) : () => true;
    // a range array read that gave none: every chunk (a plan never waits for it again)
    return this.#read.has(L) ? () => true : null;
  }

  /** [min, max] per chunk of level L when known for every chunk (its range array, or every chunk's learnt), else null. */
  knownRanges(L: number): Float32Array | null {
    const lv = this.levels[L];
    if (!lv) return null;
    if (this.store.levels[L].rangesPath) return lv.ranges;
    return this.learnt.knownCount(L) === chunkCount(lv.layout) ? this.learnt.level(L) : null;
  }

  /**
   * The store's value range: its metadata, else the finest level whose chunk
   * ranges are (partly) known: its range array, or what was learnt of it as
   * chunks arrived. Null while none is.
   */
  get valueRange(): [number, number] | null {
    const known = this.levels.map((lv) => ({
      ranges: this.store.levels[lv.index].rangesPath
        ? lv.ranges
        : this.learnt.knownCount(lv.index) > 0
          ? this.learnt.level(lv.index)
          : null,
    }));
    return storeValueRange(this.store, known);
  }

  /**
   * Learns the ranges of the chunks a step's surfaces read whose range is
   * not known (levels without range arrays), from the block ranges the
   * surfaces were just computed with: valid while no chunk has been put into
   * or evicted from that level's pool since and `current` holds (the surface
   * is still the level's, the stream alive; a finer step fetching meanwhile
   * does not spoil it). Reduced per slot on the GPU, one batch after the
   * other (learnSlotRanges); recorded as they arrive (learnSettled).
   */
  learn<F extends Pick<LevelSurface, 'readSlotRanges'>>(
    levels: readonly { level: number; volume: V; surface: F; drawn: ChunkIndex[]; ghosts: ChunkIndex[] }[],
    current: (l: { level: number; surface: F }) => boolean,
  ): void {
    for (const l of levels) {
      if (this.store.levels[l.level].rangesPath) continue;
      const changes = this.#changes[l.level];
      const valid = () => this.#changes[l.level] === changes && current(l);
      const chunks = [...l.drawn, ...l.ghosts];
      this.#learning = this.#learning.then(() => learnSlotRanges(this.learnt, l.level, chunks, l.volume, l.surface, valid));
    }
  }

  /** Resolves when the learnt ranges asked for so far are recorded. */
  learnSettled(): Promise<void> {
    return this.#learning;
  }

  /**
   * GPU bytes one wanted chunk of level L costs: its pool slot, the
   * surface's per-block state, and its share of the surface's cache and
   * vertex buffers: what the level's last surface took per wanted chunk,
   * or before one was made, a guess (half its blocks active, a chunk the
   * surface crosses).
   */
  chunkCost(L: number): number {
    const layout = this.levels[L].layout;
    return residentChunkBytes(layout) + (this.#surfaceCost[L] ?? guessedSurfaceBytesPerChunk(layout, this.gpu.cacheOnly));
  }

  /** What level L's surface took (or, `atLeast`, needed) per wanted chunk: the cost the next plan uses. */
  recordCost(L: number, bytesPerChunk: number, atLeast = false): void {
    this.#surfaceCost[L] = atLeast ? Math.max(this.#surfaceCost[L] ?? 0, bytesPerChunk) : bytesPerChunk;
  }

  /** Whether every chunk the step wants is resident. */
  resident(step: Step): boolean {
    return step.wanted.every((w, L) => w.length === 0 || (this.levels[L].volume !== null && w.every((c) => this.levels[L].volume!.has(c))));
  }

  /** Marks the step's wanted chunks as just wanted (least recently wanted go first) and lists those not resident, in fetch order (coarsest level first). */
  missing(step: Step): { missing: Set<number>; order: { level: number; chunk: ChunkIndex }[] } {
    const missing = new Set<number>();
    const order: { level: number; chunk: ChunkIndex }[] = [];
    for (let L = this.levels.length - 1; L >= 0; L--) {
      const lv = this.levels[L];
      for (const c of step.wanted[L]) {
        if (lv.lru.has(c)) {
          lv.lru.delete(c);
          lv.lru.set(c, true);
        }
        if (!lv.volume!.has(c)) {
          missing.add(key(L, c));
          order.push({ level: L, chunk: c });
        }
      }
    }
    return { missing, order };
  }

  /**
   * Gives a level's pool room for `keep` (what the step wants and what is on
   * screen): idle chunks are evicted first (least recently wanted), then the
   * pool grows within `free()` bytes, after the pools of levels `inUse` does
   * not hold gave theirs back. Returns why it cannot, or null.
   */
  fitPool(
    lv: LevelState<V>,
    keep: ReadonlySet<ChunkIndex>,
    free: () => number,
    inUse: (L: number) => boolean,
    budgetBytes: number,
  ): string | null {
    const n = Math.max(1, keep.size);
    const v = lv.volume;
    if (v && v.poolChunks >= n) return null;
    const extraFor = (chunks: number) =>
      this.gpu.poolBytesFor(lv.layout, chunks) - (v?.poolBytes ?? 0) + estimateFixedBytes(lv.layout, chunks);
    // room to grow into (fewer resizes, each of which makes the level's surface again), else exactly what is asked
    let target = Math.min(chunkCount(lv.layout), Math.max(n, Math.ceil((v?.poolChunks ?? 0) * 1.25)));
    if (extraFor(target) > free()) for (const other of this.levels) if (other !== lv && !inUse(other.index)) this.dropPool(other);
    if (extraFor(target) > free()) target = n;
    if (extraFor(target) > free())
      return (
        `level ${lv.index} needs ${n} chunks (${mib(n * lv.layout.chunkBytes)} MiB) and ${mib(estimateFixedBytes(lv.layout, n))} MiB ` +
        `of per-block state for its surface for this step; the budget of ${mib(budgetBytes)} MiB has ${mib(Math.max(0, free()))} MiB free`
      );
    this.#changes[lv.index]++;
    if (v) v.resize(Math.max(target, v.residentCount));
    else lv.volume = this.gpu.createVolume(lv.layout, target);
    return null;
  }

  /**
   * Room in each level's pool for what `step` wants and what is on screen
   * (`shownWanted`, per level): null, or the level that has none and why.
   */
  fitStep(
    step: Step,
    shownWanted: readonly ChunkIndex[][],
    free: () => number,
    inUse: (L: number) => boolean,
    budgetBytes: number,
  ): { level: number; reason: string } | null {
    for (let L = 0; L < this.levels.length; L++) {
      if (step.wanted[L].length === 0 && !step.levels.includes(L)) continue;
      const keep = new Set([...step.wanted[L], ...(shownWanted[L] ?? [])]);
      const reason = this.fitPool(this.levels[L], keep, free, inUse, budgetBytes);
      if (reason) return { level: L, reason };
    }
    return null;
  }

  /** Sets slots aside for the step's missing chunks (keys level * 2^32 + chunk), in its order: slots follow the plan, not arrivals. */
  reserve(step: Step, missing: ReadonlySet<number>): void {
    for (let L = 0; L < this.levels.length; L++) {
      const v = this.levels[L].volume;
      if (v && step.wanted[L].length > 0) v.reserve(step.wanted[L].filter((c) => missing.has(key(L, c))));
    }
  }

  /** Lets a level's pool go (its chunks stay in the fetcher's CPU cache). */
  dropPool(lv: LevelState<V>): void {
    if (!lv.volume) return;
    this.#changes[lv.index]++;
    lv.volume.destroy();
    lv.volume = null;
    lv.lru.clear();
  }

  /** Puts an arrived chunk into its level's pool (putArrived: a full pool evicts what `keep` does not hold). */
  put(level: number, chunk: ChunkIndex, bytes: Uint8Array, keep: (c: ChunkIndex) => boolean): void {
    putArrived(this.levels[level], chunk, bytes, keep, () => this.#changes[level]++);
  }

  /** GPU bytes of the pools. */
  get poolBytes(): number {
    return this.levels.reduce((a, l) => a + (l.volume?.poolBytes ?? 0), 0);
  }

  destroy(): void {
    for (const l of this.levels) {
      l.volume?.destroy();
      l.volume = null;
    }
  }
}

const mib = (b: number) => (b / 2 ** 20).toFixed(1);
