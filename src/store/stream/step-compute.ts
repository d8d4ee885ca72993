// The surfaces of a step of the store stream (store-stream.ts), once its
// chunks are resident: each level the step uses, finest first, over its pool
// restricted by chunk roles (drawn chunks emit, ghosts lend their voxels and,
// as skirts, a one-cell overlap over level seams), with the surface made for
// the pool's capacity and capped by what the budget leaves; what each took
// per wanted chunk is recorded (the cost model the next plan uses). Several
// isovalues (several surfaces) are computed one after another on each
// level's surface (one block cache: a block decodes once for all), the
// others copied as they are made, the step's own isovalue last (drawn live
// or from its present() copy); a copy the step on screen holds for the same
// level, chunks and isovalue is kept rather than computed again.
import { isAbort } from '../zarr/errors.ts';
import type { LevelStats, LevelSurface } from '../stream-port.ts';
import type { StreamLevels } from './stream-levels.ts';
import type { StreamMemory } from './stream-memory.ts';
import type { StreamSurfaces } from './stream-surfaces.ts';
import {
  type BudgetStop,
  type CopyOf,
  type CutLevelShown,
  type LevelOther,
  type RoleVolume,
  type ShownCut,
  type Step,
  sameRoles,
} from './stream-types.ts';

/** The step's levels computed; a level that did not fit (the caller coarsens or stops); stale (newer request); or an error. */
export type StepSurfaces<V, S, F> =
  | { levels: CutLevelShown<V, S, F>[] }
  | { stop: BudgetStop }
  | { stale: true }
  | { error: Error; level: number };

export async function computeStep<V extends RoleVolume, S extends LevelStats, F extends LevelSurface<S>>(
  step: Step,
  iso: number,
  /** The other isovalues drawn with it (each level's `others`, in this order). */
  others: readonly number[],
  parts: {
    pools: StreamLevels<V>;
    surfaces: StreamSurfaces<V, S, F>;
    memory: StreamMemory<V, S, F>;
    /** Ghosts as skirts (ChunkedVolume's 'skirt' role). */
    skirts: boolean;
    /** The step is drawn from copies (their bytes count in the cost). */
    snapshots: boolean;
    /** The step on screen: copies of other surfaces it holds for the same level and chunks are kept. */
    previous: ShownCut<V, S, F> | null;
  },
  stale: () => boolean,
): Promise<StepSurfaces<V, S, F>> {
  const { pools, surfaces, memory, previous } = parts;
  const budget = memory.budget.bytes;
  const levels: CutLevelShown<V, S, F>[] = [];
  let computing = step.finest;
  // copies made here: let go unless the step is returned
  const made: CopyOf<F>[] = [];
  let done = false;
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
      const kept = previous && !previous.frozen ? previous.levels.find((l) => l.level === L && sameRoles(l, step, L)) : undefined;
      const levelOthers: LevelOther<S, CopyOf<F>>[] = [];
      let otherBytes = 0;
      for (const other of others) {
        const same = kept?.others.find((o) => o.iso === other);
        if (same) {
          levelOthers.push(same);
          otherBytes += same.copy.byteSize;
          continue;
        }
        if (!surface.copy) throw new Error('StoreStream: several isovalues need surfaces that copy (LevelSurface.copy)');
        surface.setMemoryBudget(memory.capFor(surface));
        const stats = await surface.compute(other);
        if (stale()) return { stale: true };
        const needs = surface.presentBytesNeeded ?? 0;
        if (needs > memory.free())
          return {
            stop: {
              level: L,
              reason: `level ${L}: a copy of the surface at ${other} needs ${mib(needs)} MiB; the budget has ${mib(Math.max(0, memory.free()))} MiB free`,
            },
          };
        const copy = surface.copy() as CopyOf<F>;
        made.push(copy);
        otherBytes += copy.byteSize;
        levelOthers.push({ iso: other, stats, copy });
      }
      surface.setMemoryBudget(memory.capFor(surface));
      const stats = await surface.compute(iso);
      if (stale()) return { stale: true };
      // what the surface holds, the copy of it that is drawn when the step shows, and the other surfaces' copies
      const drawnCopy = parts.snapshots ? (surface.presentBytesNeeded ?? 0) : 0;
      // a cache-only surface (rays): what its active blocks need, not the headroom its cache grew into where
      // the budget had room (a plan that counted the headroom would leave the budget's last fifth to it)
      const cache = pools.gpu.cacheOnly ? (stats.cacheBytesNeeded ?? stats.cacheBytes) : stats.cacheBytes;
      pools.recordCost(L, (cache + stats.vertexBytes + drawnCopy + otherBytes) / Math.max(1, step.wanted[L].length));
      levels.push({ level: L, volume: pool, surface, stats, others: levelOthers, drawn: [...step.drawn[L]], ghosts: [...step.ghosts[L]] });
    }
    done = true;
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
  } finally {
    if (!done) for (const c of made) c.destroy();
  }
  return { levels };
}

const mib = (b: number) => (b / 2 ** 20).toFixed(1);
