// The surfaces of a step of the store stream (store-stream.ts), once its
// chunks are resident: each level the step uses, finest first, over its pool
// restricted by chunk roles (drawn chunks emit, ghosts lend their voxels and,
// as skirts, a one-cell overlap over level seams), with the surface made for
// the pool's capacity and capped by what the budget leaves; what each took
// per wanted chunk is recorded (the cost model the next plan uses).
import { isAbort } from '../zarr/errors.ts';
import type { LevelStats, LevelSurface } from '../stream-port.ts';
import type { StreamLevels } from './stream-levels.ts';
import type { StreamMemory } from './stream-memory.ts';
import type { StreamSurfaces } from './stream-surfaces.ts';
import type { BudgetStop, CutLevelShown, RoleVolume, Step } from './stream-types.ts';

/** The step's levels computed; a level that did not fit (the caller coarsens or stops); stale (newer request); or an error. */
export type StepSurfaces<V, S, F> =
  | { levels: CutLevelShown<V, S, F>[] }
  | { stop: BudgetStop }
  | { stale: true }
  | { error: Error; level: number };

export async function computeStep<V extends RoleVolume, S extends LevelStats, F extends LevelSurface<S>>(
  step: Step,
  iso: number,
  parts: {
    pools: StreamLevels<V>;
    surfaces: StreamSurfaces<V, S, F>;
    memory: StreamMemory<V, S, F>;
    /** Ghosts as skirts (ChunkedVolume's 'skirt' role). */
    skirts: boolean;
    /** The step is drawn from copies (their bytes count in the cost). */
    snapshots: boolean;
  },
  stale: () => boolean,
): Promise<StepSurfaces<V, S, F>> {
  const { pools, surfaces, memory } = parts;
  const budget = memory.budget.bytes;
  const levels: CutLevelShown<V, S, F>[] = [];
  let computing = step.finest;
  try {
    for (const L of step.levels) {
      computing = L;
      const lv = pools.levels[L];
      const pool = lv.volume!;
      pool.setRoles(step.drawn[L], step.ghosts[L], { skirts: parts.skirts });
      const noRoom = surfaces.noRoom(L, pool, lv.layout, memory.free(), budget);
      if (noRoom) return { stop: { level: L, reason: noRoom } };
      const surface = await surfaces.surfaceFor(L, pool, lv.layout, memory.free(), () => stale() || lv.volume !== pool);
      if (!surface) return { stale: true };
      surface.setMemoryBudget(memory.capFor(surface));
      const stats = await surface.compute(iso);
      if (stale()) return { stale: true };
      // what the surface holds, and the copy of it that is drawn when the step shows
      const drawnCopy = parts.snapshots ? (surface.presentBytesNeeded ?? 0) : 0;
      pools.recordCost(L, (stats.cacheBytes + stats.vertexBytes + drawnCopy) / Math.max(1, step.wanted[L].length));
      levels.push({ level: L, volume: pool, surface, stats, drawn: [...step.drawn[L]], ghosts: [...step.ghosts[L]] });
    }
  } catch (e) {
    if (stale() || isAbort(e) || (e as Error).name === 'IsosurfaceSupersededError') return { stale: true };
    if ((e as Error).name === 'IsosurfaceBudgetError') {
      // what the surface needed, per wanted chunk: the cost the next plan uses
      const needed = (e as { neededBytes?: number }).neededBytes;
      if (needed !== undefined && Number.isFinite(needed))
        pools.recordCost(computing, needed / Math.max(1, step.wanted[computing].length), true);
      return { stop: { level: computing, reason: (e as Error).message } };
    }
    return { error: e as Error, level: step.finest };
  }
  return { levels };
}
