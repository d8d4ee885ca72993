// One step of a view's refinement (../stream/cut-planner.ts): the cut
// coarsened to levels >= k, a region whose target is finer than k drawn by
// its ancestor at level k (still balanced, still covering every region
// once), and per level what that draws: its leaves, the drawn chunks (the
// leaves the surface needs), the ghosts (needed +x/+y/+z and diagonal
// neighbours of leaves that are not leaves: their voxels complete the drawn
// chunks' upper cells; none in a nested cut for rays, ViewCut.nested) and
// the chunks wanted, nearest to the eye first.
import type { ChunkIndex, ChunkLevelLayout } from '../types.ts';
import type { ViewCut } from './cut.ts';

/**
 * One step of a refinement: per level, the regions it covers (leaves), the
 * chunks drawn there that hold part of the surface, the ghosts (chunks that
 * only lend their voxels to the drawn chunks' upper cells) and the chunks
 * wanted resident, in fetch order. `levels`: the levels whose surfaces the
 * step computes, finest first.
 */
export interface Step {
  finest: number;
  levels: number[];
  leaves: ChunkIndex[][];
  drawn: Set<ChunkIndex>[];
  ghosts: Set<ChunkIndex>[];
  wanted: ChunkIndex[][];
}

/**
 * Step k of `cut`. `needs(L)`: which chunks of level L the surface needs
 * (null: unknown, every chunk); `eye` and `voxelSize` in the cut's world
 * (level-0 voxel (i, j, k) at (i, j, k) * voxelSize); `scales[L]`: level-0
 * voxels per voxel of level L, per axis.
 */
export function cutStep(
  cut: ViewCut,
  k: number,
  layouts: readonly ChunkLevelLayout[],
  scales: readonly (readonly [number, number, number])[],
  needs: (level: number) => ((chunk: ChunkIndex) => boolean) | null,
  eye: readonly [number, number, number],
  voxelSize: readonly [number, number, number],
): Step {
  const n = layouts.length;
  const leaves: Set<ChunkIndex>[] = Array.from({ length: n }, () => new Set());
  const edge0 = (L: number, a: number) => layouts[L].chunkEdge * scales[L][a];
  for (const node of cut.nodes) {
    if (node.level >= k) {
      leaves[node.level].add(node.chunk);
      continue;
    }
    const [gx, gy] = layouts[k].chunkGrid;
    const a = node.coords.map((c, axis) => Math.floor((c * edge0(node.level, axis)) / edge0(k, axis)));
    leaves[k].add(a[0] + gx * (a[1] + gy * a[2]));
  }
  const drawn: Set<ChunkIndex>[] = [];
  const ghosts: Set<ChunkIndex>[] = [];
  const wanted: ChunkIndex[][] = [];
  for (let L = 0; L < n; L++) {
    const need = leaves[L].size > 0 ? (needs(L) ?? (() => true)) : () => false;
    const { chunkGrid: g } = layouts[L];
    const d = new Set<ChunkIndex>();
    const gh = new Set<ChunkIndex>();
    for (const c of leaves[L]) {
      if (need(c)) d.add(c);
      // a nested cut (for rays) has no ghosts: its coarser levels trace the drawn chunks' last cells
      if (cut.nested) continue;
      const x = c % g[0];
      const y = Math.floor(c / g[0]) % g[1];
      const z = Math.floor(c / (g[0] * g[1]));
      for (let o = 1; o < 8; o++) {
        const ux = x + (o & 1);
        const uy = y + ((o >> 1) & 1);
        const uz = z + ((o >> 2) & 1);
        if (ux >= g[0] || uy >= g[1] || uz >= g[2]) continue;
        const u = ux + g[0] * (uy + g[1] * uz);
        if (!leaves[L].has(u) && need(u)) gh.add(u);
      }
    }
    drawn.push(d);
    ghosts.push(gh);
    wanted.push(nearestFirst(layouts[L], scales[L], [...d, ...gh], eye, voxelSize));
  }
  const levels = drawn.map((d, L) => (d.size > 0 ? L : -1)).filter((L) => L >= 0);
  return { finest: k, levels, leaves: leaves.map((s) => [...s]), drawn, ghosts, wanted };
}

/** Chunks of level L by their centre's distance to the eye, nearest first (ties: ascending chunk). */
function nearestFirst(
  layout: ChunkLevelLayout,
  scale: readonly [number, number, number],
  chunks: ChunkIndex[],
  eye: readonly [number, number, number],
  s: readonly [number, number, number],
): ChunkIndex[] {
  const { chunkGrid: g, chunkEdge } = layout;
  const dist = (c: ChunkIndex) => {
    const p = [c % g[0], Math.floor(c / g[0]) % g[1], Math.floor(c / (g[0] * g[1]))];
    let d = 0;
    for (let a = 0; a < 3; a++) d += ((p[a] + 0.5) * chunkEdge * scale[a] * s[a] - eye[a]) ** 2;
    return d;
  };
  return chunks
    .map((c) => [dist(c), c] as const)
    .sort((a, b) => a[0] - b[0] || a[1] - b[1])
    .map(([, c]) => c);
}
