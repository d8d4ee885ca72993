// What the store stream (store-stream.ts) takes and gives: the pools it
// draws (chunk roles), the steps its planner makes (planner.ts), the view,
// the step on screen, and its per-level state.
import type { ChunkRoleOptions } from '../../zfp/chunked-volume.ts';
import type { LevelVolume, SurfaceCopy } from '../stream-port.ts';
import type { ChunkIndex, ChunkLevelLayout } from '../types.ts';
import type { ViewCut } from '../view/cut.ts';
import type { Step } from '../view/step.ts';

export type { Step } from '../view/step.ts';
export { DEFAULT_TOLERANCE_PX, type ViewSpec } from '../view/cut-types.ts';

/** A pool whose chunks can be drawn, ghosts or idle (ChunkedVolume.setRoles). */
export interface RoleVolume extends LevelVolume {
  setRoles(drawn: ReadonlySet<ChunkIndex> | null, ghosts: ReadonlySet<ChunkIndex>, options?: ChunkRoleOptions): void;
}

/** The copy type a level's surface makes (LevelSurface.copy): Isosurface's is a SurfaceSnapshot. */
export type CopyOf<F> = F extends { copy?(): infer C } ? C : SurfaceCopy;

/** Another surface of a level of the step: the level's surface at `iso`, copied (ShownCut.others). */
export interface LevelOther<S, C> {
  iso: number;
  stats: S;
  copy: C;
}

/** One level of the surface on screen. */
export interface CutLevelShown<V, S, F> {
  level: number;
  volume: V;
  /** At the step's `iso`, drawn from its present() copy (or live: the CLI). */
  surface: F;
  stats: S;
  /** The step's other isovalues (ShownCut.others, in that order), each a copy of this level's surface at it. */
  others: LevelOther<S, CopyOf<F>>[];
  /** Chunks drawn at this level that hold part of the surface (the others have none). */
  drawn: ChunkIndex[];
  ghosts: ChunkIndex[];
}

export interface ShownCut<V, S, F> {
  iso: number;
  /** Other isovalues drawn from the same resident chunks (several surfaces): each level's `others`. */
  others: number[];
  /** The finest level of this step; `final` when it is the plan's last step. */
  step: number;
  final: boolean;
  levels: CutLevelShown<V, S, F>[];
  /** The view's cut this step leads to (null: a plan by level, not by view). */
  cut: ViewCut | null;
  /** Leaves drawn per level in this step (needed or not): the regions each level covers. */
  leaves: ChunkIndex[][];
  /**
   * Its surfaces were released to their drawn copies (a lowered budget, a
   * suspended stream): it is still drawn, but nothing is computed on it and
   * the next refinement replaces it.
   */
  frozen?: boolean;
}

export interface LevelState<V> {
  index: number;
  layout: ChunkLevelLayout;
  ranges: Float32Array | null;
  nb: Float32Array | null;
  reading: Promise<void> | null;
  volume: V | null;
  /** Resident chunks, least recently wanted first. */
  lru: Map<ChunkIndex, true>;
}

/** A step that did not fit the budget: the level and why; `coarser` when the cut could be made coarser. */
export interface BudgetStop {
  level: number;
  reason: string;
  coarser?: boolean;
}

/** Chunks a step waits for (keys level * 2^32 + chunk), and per level what must stay resident meanwhile. */
export interface Waiting {
  missing: Set<number>;
  done: () => void;
  keep: Set<number>[];
}

/** Whether `shown` is this step at these isovalues (the same levels, drawn chunks and ghosts per level). */
export function showsStep(
  shown: ShownCut<unknown, unknown, unknown> | null,
  step: Step,
  iso: number,
  others: readonly number[] = [],
): boolean {
  if (!shown || shown.frozen || shown.iso !== iso || shown.levels.length !== step.levels.length) return false;
  if (shown.others.length !== others.length || shown.others.some((o, i) => o !== others[i])) return false;
  return shown.levels.every((l) => step.levels.includes(l.level) && sameRoles(l, step, l.level));
}

/** Whether a level shown had the step's drawn chunks and ghosts at level L. */
export function sameRoles(l: { drawn: readonly ChunkIndex[]; ghosts: readonly ChunkIndex[] }, step: Step, L: number): boolean {
  return (
    l.drawn.length === step.drawn[L].size &&
    l.ghosts.length === step.ghosts[L].size &&
    l.drawn.every((c) => step.drawn[L].has(c)) &&
    l.ghosts.every((c) => step.ghosts[L].has(c))
  );
}

/** The copies of the other surfaces a step holds. */
export function copiesOf<C>(shown: { levels: readonly { others: readonly { copy: C }[] }[] } | null): Set<C> {
  return new Set((shown?.levels ?? []).flatMap((l) => l.others.map((o) => o.copy)));
}

/** Per level (of `levels`), the chunks the step on screen reads (drawn and ghosts); none when it is frozen (its pools are gone). */
export function shownWanted(shown: ShownCut<unknown, unknown, unknown> | null, levels: number): ChunkIndex[][] {
  const out: ChunkIndex[][] = Array.from({ length: levels }, () => []);
  if (shown?.frozen) return out;
  for (const l of shown?.levels ?? []) out[l.level] = [...l.drawn, ...l.ghosts];
  return out;
}

export const key = (level: number, chunk: ChunkIndex) => level * 2 ** 32 + chunk;
