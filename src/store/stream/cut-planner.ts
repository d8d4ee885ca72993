// The plan by view (stream/planner.ts): for the isovalue and the camera, the
// cut (cut.ts: which chunk of which level draws each region, within the
// budget); step k is the cut coarsened to levels >= k (step.ts), from the
// coarsest level the cut uses down to its finest, so the first surface comes
// from the coarsest level at once and each finer step replaces its parents.
// The cut itself is the view's (../view/).
import { viewCut } from '../view/cut.ts';
import { cutStep, type Step } from '../view/step.ts';
import type { Planner, PlanInput, StreamPlan } from './planner.ts';

export class CutPlanner implements Planner {
  readonly needsView = true;

  plan(input: PlanInput): StreamPlan {
    const { view, layouts } = input;
    if (!view) throw new Error('CutPlanner: a plan by view needs a view');
    const cut = viewCut({
      levels: layouts.map((l, L) => ({ dims: l.dims, chunkEdge: l.chunkEdge, chunkGrid: l.chunkGrid, scale: input.scales[L] })),
      voxelSize: input.voxelSize,
      camera: view.camera,
      tolerancePx: view.tolerancePx,
      finest: Math.max(input.finestUsable, Math.min(input.finest, input.coarsest)),
      coarsest: input.coarsest,
      needs: (L) => input.needs(L),
      chunkBytes: (L) => input.chunkCost(L),
      budgetBytes: input.budgetBytes,
      seen: input.seen ?? null,
    });
    if (cut.wantsRanges.length > 0) return { steps: [], wantsRanges: cut.wantsRanges, coarsenable: false, cut };
    const step = (k: number): Step => cutStep(cut, k, layouts, input.scales, (L) => input.needs(L), view.camera.eye, input.voxelSize);
    const drawnAt = cut.levels.map((l, L) => (l.drawn.length > 0 ? L : -1)).filter((L) => L >= 0);
    const steps: Step[] = [];
    if (drawnAt.length > 0) for (let k = Math.max(...drawnAt); k >= Math.min(...drawnAt); k--) steps.push(step(k));
    // a cut that draws no chunk: one empty step, shown, so the page draws nothing at this isovalue
    else steps.push(step(input.coarsest));
    // smaller budgets make the cut coarser while some region is drawn finer than the coarsest level
    const coarsenable = drawnAt.length > 0 && Math.min(...drawnAt) < input.coarsest;
    return { steps, wantsRanges: [], coarsenable, cut };
  }
}
