// What a store stream (store-stream.ts) holds on the GPU against its budget:
// its pools (stream-levels.ts) and surfaces (stream-surfaces.ts), counted
// where they are made, and the budget they are held against (shared with
// whatever else the page holds: gpu/budget.ts). The room a step has, what
// giving back means (what is not on screen first, then everything but the
// copies the step on screen is drawn from), and the figures.
import type { GpuBudget } from '../../gpu/budget.ts';
import type { LevelStats, LevelSurface, StreamGpu, StreamGpuBytes } from '../stream-port.ts';
import type { StreamLevels } from './stream-levels.ts';
import type { StreamSurfaces } from './stream-surfaces.ts';
import type { CutLevelShown, RoleVolume, ShownCut } from './stream-types.ts';

/** Kept free within the budget for short-lived buffers (statistics and readback staging, uniforms). */
export const RESERVE_BYTES = 1 << 20;

export class StreamMemory<V extends RoleVolume, S extends LevelStats, F extends LevelSurface<S>> {
  constructor(
    readonly budget: GpuBudget,
    readonly gpu: Pick<StreamGpu<V, S, F>, 'allocatedBytes'>,
    readonly pools: StreamLevels<V>,
    readonly surfaces: StreamSurfaces<V, S, F>,
  ) {}

  /** Bytes that may still be allocated (the reserve kept). */
  free(): number {
    return this.budget.bytes - RESERVE_BYTES - this.budget.heldBytes;
  }

  /** Whether more is held than the budget allows (the reserve kept). */
  get over(): boolean {
    return this.free() < 0;
  }

  /**
   * The bytes a plan may count on with `share` of the budget: not what
   * others hold against it (the page's store being replaced), nor the copies
   * this stream's next step replaces (parked surfaces).
   */
  planBytes(share: number): number {
    const elsewhere = Math.max(0, this.budget.heldBytes - this.gpu.allocatedBytes);
    return Math.max(0, this.budget.bytes - RESERVE_BYTES - elsewhere - this.surfaces.parkedBytes) * share;
  }

  /** The cap of a surface's cache and vertices: what the rest of the budget leaves it. */
  capFor(surface: F): number {
    return Math.max(1, this.budget.bytes - RESERVE_BYTES - (this.budget.heldBytes - surface.budgetedBytes));
  }

  /**
   * Why the copies of a step's surfaces (`levels`, of levels `used`) do not
   * fit beside the rest, or null: what they need beyond the copies they
   * replace, less what the surfaces that step lets go hold.
   */
  copiesRefusal(used: readonly number[], levels: readonly CutLevelShown<V, S, F>[]): string | null {
    const freed = this.surfaces.bytesOutside(used);
    const copies = levels.reduce((a, l) => a + (l.surface.presentBytesNeeded ?? 0) - (l.surface.presentedBytes ?? 0), 0);
    if (this.budget.heldBytes - freed + copies <= this.budget.bytes - RESERVE_BYTES / 2) return null;
    return `the step's surfaces and the copies drawn of them need ${copies} B more than the budget of ${this.budget.bytes} B leaves`;
  }

  /**
   * Lets go of the surfaces and pools of levels that the step on screen does
   * not draw, and empties the block caches of those that stay (their drawn
   * meshes stay; a cache regrows as its surface needs it).
   */
  releaseUnshown(shown: ShownCut<V, S, F> | null): void {
    const levels = (shown?.levels ?? []).map((l) => l.level);
    this.surfaces.letGoUnshown(onScreen(shown));
    for (const lv of this.pools.levels) if (!levels.includes(lv.index)) this.pools.dropPool(lv);
    this.surfaces.trimCaches();
  }

  /**
   * Keeps only the copies the step on screen is drawn from: every pool and
   * every surface's working state goes (chunks stay in the fetcher's CPU
   * cache); the step on screen is then frozen (the next refinement replaces it).
   */
  releaseToCopies(shown: ShownCut<V, S, F> | null): ShownCut<V, S, F> | null {
    this.surfaces.releaseToCopies(onScreen(shown));
    for (const lv of this.pools.levels) this.pools.dropPool(lv);
    return shown && { ...shown, frozen: true };
  }

  /**
   * Lets go of everything, the copies on screen too (they alone were over
   * the budget): the step on screen is left with no level to draw until the
   * next step shows.
   */
  releaseAll(shown: ShownCut<V, S, F> | null): ShownCut<V, S, F> | null {
    this.surfaces.destroy();
    for (const lv of this.pools.levels) this.pools.dropPool(lv);
    return shown && { ...shown, levels: [], frozen: true };
  }

  /** GPU bytes the stream holds now: pools, surfaces, and of these the cache and vertex buffers of the step on screen. */
  bytes(shown: ShownCut<V, S, F> | null): StreamGpuBytes {
    const pools = this.pools.poolBytes;
    const total = this.gpu.allocatedBytes;
    const levels = shown && !shown.frozen ? shown.levels : [];
    return {
      pools,
      surfaces: total - pools,
      total,
      cache: levels.reduce((a, l) => a + l.stats.cacheBytes, 0),
      vertices: levels.reduce((a, l) => a + l.stats.vertexBytes, 0),
    };
  }
}

/** The surfaces a step on screen draws. */
function onScreen<F>(shown: ShownCut<unknown, unknown, F> | null): Set<F> {
  return new Set((shown?.levels ?? []).map((l) => l.surface));
}
