// Which chunks of a level a surface at `iso` needs, and in which order to
// fetch them. The rule is the pipeline's active-block test one level up
// (src/isosurface/README.md, "Active blocks with one compare"): a chunk is
// needed iff lo < iso <= hi over its 27-chunk neighbourhood's range. A cell
// that emits triangles has a corner below iso and one at or above it; its
// corners lie in at most 8 chunks that are each other's neighbours, so each
// of those chunks' neighbourhood range covers iso: every chunk an emitting
// cell touches is needed, and a non-resident chunk never hides a triangle.
import type { ChunkIndex, ChunkLevelLayout } from './types.ts';

type Grid = readonly [number, number, number];

/**
 * Per chunk, [min, max] over itself and its 26 neighbours. `ranges` is
 * [min, max] per chunk in chunk-index order; NaN (unknown: not fetched yet,
 * no range array) makes a neighbourhood (-inf, +inf), i.e. always needed.
 */
export function neighbourhoodRanges(grid: Grid, ranges: Float32Array): Float32Array {
  const [gx, gy, gz] = grid;
  const n = gx * gy * gz;
  if (ranges.length !== 2 * n) throw new RangeError(`ranges hold ${ranges.length / 2} chunks, the grid ${n}`);
  // separable: min/max along x, then y, then z (three passes of 3 taps)
  let lo = new Float64Array(n);
  let hi = new Float64Array(n);
  for (let i = 0; i < n; i++) {
    const a = ranges[2 * i],
      b = ranges[2 * i + 1];
    // unknown (either end NaN): (-inf, +inf), as neighbourhoodOf reads it
    const unknown = Number.isNaN(a) || Number.isNaN(b);
    lo[i] = unknown ? -Infinity : a;
    hi[i] = unknown ? Infinity : b;
  }
  const strides = [1, gx, gx * gy];
  for (let axis = 0; axis < 3; axis++) {
    const s = strides[axis];
    const len = grid[axis];
    const lo2 = new Float64Array(n);
    const hi2 = new Float64Array(n);
    for (let i = 0; i < n; i++) {
      const c = Math.floor(i / s) % len;
      let l = lo[i],
        h = hi[i];
      if (c > 0) {
        l = Math.min(l, lo[i - s]);
        h = Math.max(h, hi[i - s]);
      }
      if (c + 1 < len) {
        l = Math.min(l, lo[i + s]);
        h = Math.max(h, hi[i + s]);
      }
      lo2[i] = l;
      hi2[i] = h;
    }
    lo = lo2;
    hi = hi2;
  }
  const out = new Float32Array(2 * n);
  for (let i = 0; i < n; i++) {
    out[2 * i] = lo[i];
    out[2 * i + 1] = hi[i];
  }
  return out;
}

/**
 * The same neighbourhood range for one chunk, read from its 27 entries of
 * `ranges` (nothing made per level: for ranges that change as chunks are
 * learnt, learnt-ranges.ts). NaN anywhere makes it (-inf, +inf).
 */
export function neighbourhoodOf(grid: Grid, ranges: Float32Array, chunk: ChunkIndex): [number, number] {
  const [gx, gy, gz] = grid;
  const x = chunk % gx;
  const y = Math.floor(chunk / gx) % gy;
  const z = Math.floor(chunk / (gx * gy));
  let lo = Infinity;
  let hi = -Infinity;
  for (let w = Math.max(0, z - 1); w <= Math.min(gz - 1, z + 1); w++)
    for (let v = Math.max(0, y - 1); v <= Math.min(gy - 1, y + 1); v++)
      for (let u = Math.max(0, x - 1); u <= Math.min(gx - 1, x + 1); u++) {
        const n = u + gx * (v + gy * w);
        const a = ranges[2 * n];
        const b = ranges[2 * n + 1];
        if (Number.isNaN(a) || Number.isNaN(b)) return [-Infinity, Infinity];
        if (a < lo) lo = a;
        if (b > hi) hi = b;
      }
  return [lo, hi];
}

/** The rule: a neighbourhood range [lo, hi] needs the surface at `iso` iff lo < iso <= hi. */
export function rangeNeeded(lo: number, hi: number, iso: number): boolean {
  return lo < iso && iso <= hi;
}

/** Whether a chunk's neighbourhood range (neighbourhoodRanges) satisfies the rule (the surface needs it). */
export function chunkNeeded(neighbourhood: Float32Array, iso: number, chunk: ChunkIndex): boolean {
  return rangeNeeded(neighbourhood[2 * chunk], neighbourhood[2 * chunk + 1], iso);
}

/** The chunks whose neighbourhood range satisfies lo < iso <= hi, in index order. */
export function chunksNeeded(neighbourhood: Float32Array, iso: number): ChunkIndex[] {
  const out: ChunkIndex[] = [];
  for (let i = 0; i < neighbourhood.length / 2; i++) {
    if (chunkNeeded(neighbourhood, iso, i)) out.push(i);
  }
  return out;
}

/** Chunk centre in level voxel coordinates. */
export function chunkCentre(layout: ChunkLevelLayout, chunk: ChunkIndex): [number, number, number] {
  const [gx, gy] = layout.chunkGrid;
  const C = layout.chunkEdge;
  const c = [chunk % gx, Math.floor(chunk / gx) % gy, Math.floor(chunk / (gx * gy))];
  return c.map((v, a) => Math.min((v + 0.5) * C, (v * C + layout.dims[a]) / 2)) as [number, number, number];
}

/**
 * Sorts chunks nearest-first to `point` (level voxel coordinates, e.g. the
 * camera's position mapped into the volume); ties by index, so the order is
 * deterministic.
 */
export function nearestFirst(
  layout: ChunkLevelLayout,
  chunks: readonly ChunkIndex[],
  point: readonly [number, number, number],
): ChunkIndex[] {
  const d = new Map<ChunkIndex, number>();
  for (const c of chunks) {
    const m = chunkCentre(layout, c);
    d.set(c, (m[0] - point[0]) ** 2 + (m[1] - point[1]) ** 2 + (m[2] - point[2]) ** 2);
  }
  return [...chunks].sort((a, b) => d.get(a)! - d.get(b)! || a - b);
}
