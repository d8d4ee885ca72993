// How the store stream (store-stream.ts) decides what to draw: a planner
// turns the isovalue (and the view, for a planner that needs one) into
// steps, coarse to fine, each of which the stream fetches, computes and
// shows whole. The stream is the same for every planner: pools, surfaces,
// the budget, snapshots, stops and retries live there; a planner only says
// which chunk of which level draws each region.
//   - by view (view/cut-planner.ts): the view's cut, step k the cut
//     coarsened to levels >= k;
//   - level by level (level-planner.ts): step L draws level L everywhere.
import type { ChunkIndex, ChunkLevelLayout } from '../types.ts';
import type { ViewCut } from '../view/cut.ts';
import type { Step, ViewSpec } from './stream-types.ts';

export interface PlanInput {
  iso: number;
  view: ViewSpec | null;
  /** Level 0's voxel size (x, y, z). */
  voxelSize: [number, number, number];
  layouts: readonly ChunkLevelLayout[];
  /** Per level, level-0 voxels one of its voxels spans on x, y and z (ZfpStore.levelScales). */
  scales: readonly (readonly [number, number, number])[];
  /** The levels the plan may use: `finest` (as asked) to `coarsest`; none finer than `finestUsable` can be drawn. */
  finest: number;
  finestUsable: number;
  coarsest: number;
  /** Why a level cannot be drawn (wider than a surface can be), or null. */
  unusable(level: number): string | null;
  /** Which chunks of level L the surface at `iso` needs; null while its range array is unread. */
  needs(level: number): ((chunk: ChunkIndex) => boolean) | null;
  /** GPU bytes one wanted chunk of level L costs (pool slot, per-block state, share of cache and vertices). */
  chunkCost(level: number): number;
  /** GPU bytes the plan may spend (a share of the budget, smaller each time a plan did not fit). */
  budgetBytes: number;
  /** Where an image's rays found the surface, per level-0 chunk (StoreStream.setSeen): a plan by view then makes a cut for rays (CutInput.seen). */
  seen?: Uint32Array | null;
}

export interface StreamPlan {
  /** Coarse to fine; the last is the plan's whole surface. */
  steps: Step[];
  /** Levels whose range arrays are read before planning again (after the steps, when there are some). */
  wantsRanges: number[];
  /** Whether a plan with a smaller budget would be coarser (a step that does not fit then tries that). */
  coarsenable: boolean;
  cut: ViewCut | null;
  /** A level the plan cannot reach, and why: the stream stops there once the steps are shown. */
  refused?: { level: number; reason: string };
}

export interface Planner {
  /** Whether the plan needs a view (setView before setIsovalue). */
  readonly needsView: boolean;
  plan(input: PlanInput): StreamPlan;
}
