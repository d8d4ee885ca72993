// The store stream's surfaces (store-stream.ts): one Isosurface per level a
// step draws, made for its pool's capacity. A surface the stream no longer
// computes on is parked: one made for a pool's old capacity (block ids are
// slot-relative, so a resized pool gets a new surface), or one released to
// its drawn copy (a lowered budget, a suspended stream). A parked surface
// is destroyed once no step on screen draws it; a surface on screen is never
// destroyed before the step that replaces it shows.
import { estimateFixedBytes } from '../level-state.ts';
import type { LevelStats, LevelSurface, StreamGpu } from '../stream-port.ts';
import type { ChunkLevelLayout } from '../types.ts';
import type { RoleVolume } from './stream-types.ts';

export class StreamSurfaces<V extends RoleVolume, S extends LevelStats, F extends LevelSurface<S>> {
  readonly #byLevel = new Map<number, { surface: F; capacity: number }>();
  /** Surfaces no longer computed on, destroyed once no step on screen draws them. */
  readonly #parked = new Set<F>();

  constructor(readonly gpu: Pick<StreamGpu<V, S, F>, 'createSurface'>) {}

  has(level: number): boolean {
    return this.#byLevel.has(level);
  }

  get(level: number): F | undefined {
    return this.#byLevel.get(level)?.surface;
  }

  /**
   * Why level L cannot have a new surface over `pool` within `free` bytes
   * (its per-level buffers and a minimal cache), or null: room enough, or
   * the level has a surface made for this pool already.
   */
  noRoom(level: number, pool: V, layout: ChunkLevelLayout, free: number, budgetBytes: number): string | null {
    if (this.#byLevel.get(level)?.capacity === pool.poolChunks) return null;
    const needs = estimateFixedBytes(layout, pool.poolChunks) + MIN_SURFACE_BYTES;
    if (needs <= free) return null;
    return (
      `level ${level}'s surface needs about ${mib(needs)} MiB of per-level buffers (ranges, maps) and a minimal cache; ` +
      `the budget of ${mib(budgetBytes)} MiB has ${mib(Math.max(0, free))} MiB free`
    );
  }

  /**
   * Level L's surface over `pool`: the one it has when made for the pool's
   * capacity, else a new one (its cache and vertices capped by what `free`
   * bytes leave beside its per-level buffers; the old one is parked);
   * undefined when `stale()` after it was made (it is let go).
   */
  async surfaceFor(level: number, pool: V, layout: ChunkLevelLayout, free: number, stale: () => boolean): Promise<F | undefined> {
    const entry = this.#byLevel.get(level);
    if (entry && entry.capacity === pool.poolChunks) return entry.surface;
    if (entry) {
      this.#parked.add(entry.surface);
      this.#byLevel.delete(level);
    }
    const surface = await this.gpu.createSurface(pool, Math.max(MIN_SURFACE_BYTES, free - estimateFixedBytes(layout, pool.poolChunks)));
    if (stale()) {
      surface.destroy();
      return undefined;
    }
    this.#byLevel.set(level, { surface, capacity: pool.poolChunks });
    return surface;
  }

  /** Bytes the surfaces of levels outside `keep` and the parked ones hold (their drawn copies included): what a step of `keep` gives back. */
  bytesOutside(keep: readonly number[]): number {
    const goes = [...this.#parked, ...[...this.#byLevel].filter(([L]) => !keep.includes(L)).map(([, e]) => e.surface)];
    return goes.reduce((a, f) => a + f.budgetedBytes + (f.presentedBytes ?? 0), 0);
  }

  /** Bytes of the parked surfaces (drawn copies of a step being replaced, surfaces of old pool capacities). */
  get parkedBytes(): number {
    let n = 0;
    for (const f of this.#parked) n += f.budgetedBytes + (f.presentedBytes ?? 0);
    return n;
  }

  /** A step of levels `keep` shows: the surfaces of other levels go, and every parked one; the levels let go, for their pools. */
  letGoOutside(keep: readonly number[]): number[] {
    const gone: number[] = [];
    for (const [L, entry] of this.#byLevel) {
      if (keep.includes(L)) continue;
      entry.surface.destroy();
      this.#byLevel.delete(L);
      gone.push(L);
    }
    for (const s of this.#parked) s.destroy();
    this.#parked.clear();
    return gone;
  }

  /** Lets go of every surface the step on screen (`onScreen`) does not draw; the levels whose surface went. */
  letGoUnshown(onScreen: ReadonlySet<F>): number[] {
    const gone: number[] = [];
    for (const [L, entry] of this.#byLevel) {
      if (onScreen.has(entry.surface)) continue;
      entry.surface.destroy();
      this.#byLevel.delete(L);
      gone.push(L);
    }
    for (const s of this.#parked) {
      if (onScreen.has(s)) continue;
      s.destroy();
      this.#parked.delete(s);
    }
    return gone;
  }

  /**
   * Keeps only the drawn copies of the surfaces on screen: each is released
   * to its copy (LevelSurface.release) and parked, the others destroyed.
   * Every level then makes a new surface for its next step.
   */
  releaseToCopies(onScreen: ReadonlySet<F>): void {
    this.letGoUnshown(onScreen);
    for (const entry of this.#byLevel.values()) {
      entry.surface.release?.();
      this.#parked.add(entry.surface);
    }
    this.#byLevel.clear();
    for (const s of this.#parked) s.release?.();
  }

  /** Empties every block cache back to its first size (the drawn meshes stay). */
  trimCaches(): void {
    for (const entry of this.#byLevel.values()) entry.surface.trimCache();
  }

  destroy(): void {
    this.letGoOutside([]);
  }
}

/** Below this, a surface's cache and vertex buffers are too small to be worth creating. */
const MIN_SURFACE_BYTES = 256 << 10;
const mib = (b: number) => (b / 2 ** 20).toFixed(1);
