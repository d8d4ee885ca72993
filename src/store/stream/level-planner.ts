// The plan level by level (planner.ts): step L draws level L everywhere (the
// chunks its surface needs at the isovalue, nearest to `focus` first), from
// the coarsest level down to the finest asked for. A level's range array is
// read when the plan first reaches it, so opening costs the same whatever
// the store's size: the plan ends at the first level whose ranges are
// unread, and goes on once they are.
import { nearestFirst } from '../plan.ts';
import type { ChunkIndex, ChunkLevelLayout } from '../types.ts';
import type { Planner, PlanInput, StreamPlan } from './planner.ts';
import type { Step } from './stream-types.ts';

export class LevelPlanner implements Planner {
  readonly needsView = false;
  /** Where "nearest first" measures from, in level-0 voxels. */
  focus: [number, number, number];

  constructor(level0: ChunkLevelLayout) {
    const d = level0.dims;
    this.focus = [d[0] / 2, d[1] / 2, d[2] / 2];
  }

  plan(input: PlanInput): StreamPlan {
    const steps: Step[] = [];
    const finest = Math.max(0, Math.min(input.finest, input.coarsest));
    for (let L = input.coarsest; L >= finest; L--) {
      const unusable = input.unusable(L);
      if (unusable) return { steps, wantsRanges: [], coarsenable: false, cut: null, refused: { level: L, reason: unusable } };
      const needs = input.needs(L);
      if (!needs) return { steps, wantsRanges: [L], coarsenable: false, cut: null };
      steps.push(this.#step(input.layouts, L, input.scales[L], needs));
    }
    return { steps, wantsRanges: [], coarsenable: false, cut: null };
  }

  #step(
    layouts: readonly ChunkLevelLayout[],
    L: number,
    scale: readonly [number, number, number],
    needs: (c: ChunkIndex) => boolean,
  ): Step {
    const layout = layouts[L];
    const [gx, gy, gz] = layout.chunkGrid;
    const needed: ChunkIndex[] = [];
    for (let c = 0; c < gx * gy * gz; c++) if (needs(c)) needed.push(c);
    const wanted = nearestFirst(layout, needed, [this.focus[0] / scale[0], this.focus[1] / scale[1], this.focus[2] / scale[2]]);
    const none = () => layouts.map(() => new Set<ChunkIndex>());
    const drawn = none();
    drawn[L] = new Set(needed);
    return {
      finest: L,
      // the level's surface is computed even when it needs no chunk (an isovalue outside the level's values: no triangles)
      levels: [L],
      leaves: layouts.map((_, l) => (l === L ? needed : [])),
      drawn,
      ghosts: none(),
      wanted: layouts.map((_, l) => (l === L ? wanted : [])),
    };
  }
}
