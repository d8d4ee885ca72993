// Which level draws each region of a step (the ray caster's region grid,
// issue 46). A step's leaves say which chunks of which level cover which
// region; a cut made for rays (cut.ts, `seen`) is nested, not a partition: a
// coarse chunk stays drawn where only some of its finer chunks are, and each
// region belongs to the finest level whose leaf covers it. The grid is the
// chunk grid of the finest level with leaves (every coarser leaf of a cut is
// a union of its chunks: the cut only splits levels that nest), one byte
// per chunk: the level that owns it, or NO_OWNER.
import type { ChunkIndex } from '../types.ts';

/** A cell of the region grid no leaf covers. */
export const NO_OWNER = 255;

export interface RegionOwners {
  /** Cells per axis (the finest leaf level's chunk grid). */
  grid: [number, number, number];
  /** A cell's edge in level-0 voxels, per axis (that level's chunk edge x its scale). */
  edge: [number, number, number];
  /** Per cell (x fastest), the level that draws it, or NO_OWNER. */
  owner: Uint8Array;
}

/**
 * The region grid of a step: `leaves[L]` the chunks of level L it covers,
 * `layouts[L]` level L's chunk grid and edge, `scales[L]` level-0 voxels per
 * voxel of L. Null when the step has no leaf. Finer levels win where leaves overlap.
 */
export function regionOwners(
  leaves: readonly (readonly ChunkIndex[])[],
  layouts: readonly { chunkEdge: number; chunkGrid: readonly [number, number, number] }[],
  scales: readonly (readonly [number, number, number])[],
): RegionOwners | null {
  const levels = leaves.map((l, L) => (l.length > 0 ? L : -1)).filter((L) => L >= 0);
  if (levels.length === 0) return null;
  if (levels[levels.length - 1] >= NO_OWNER)
    throw new RangeError(`regionOwners: level ${levels[levels.length - 1]} cannot be named in a byte`);
  const f = levels[0];
  const grid = [...layouts[f].chunkGrid] as [number, number, number];
  const edge = scales[f].map((s) => s * layouts[f].chunkEdge) as [number, number, number];
  const owner = new Uint8Array(grid[0] * grid[1] * grid[2]).fill(NO_OWNER);
  // coarsest first, so finer leaves overwrite
  for (let i = levels.length - 1; i >= 0; i--) {
    const L = levels[i];
    const g = layouts[L].chunkGrid;
    const e = scales[L].map((s) => s * layouts[L].chunkEdge);
    for (const c of leaves[L]) {
      const q = [c % g[0], Math.floor(c / g[0]) % g[1], Math.floor(c / (g[0] * g[1]))];
      const lo = q.map((v, a) => Math.floor((v * e[a]) / edge[a]));
      const hi = q.map((v, a) => Math.min(grid[a], Math.ceil(((v + 1) * e[a]) / edge[a])));
      for (let z = lo[2]; z < hi[2]; z++)
        for (let y = lo[1]; y < hi[1]; y++) owner.fill(L, lo[0] + grid[0] * (y + grid[1] * z), hi[0] + grid[0] * (y + grid[1] * z));
    }
  }
  return { grid, edge, owner };
}
