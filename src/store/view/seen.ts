// Where an image's rays found the surface, as a cut for rays asks for it
// (CutInput.seen, issue 46): per level-0 chunk, 1 + the pixels whose first
// hit lies in it, or 1 where a point GUARD_VOXELS voxels of the hit's level
// before or after a hit along its ray lies (the most any image gave). The hit of a coarse level is where the finer surface is to be
// found to within about a coarse voxel, in front of it or behind: the guard
// asks for the finer chunks on both sides, so that the next image's hit does
// not land in a chunk nobody asked for (it would be asked for by that image).
// In a nested cut a coarser level's rays trace the last cells of a finer
// region below one it owns (the finer level has no voxels past its chunk),
// so a hit just below a region owned by a coarser level may be that level's:
// the chunk above the seam counts as seen too, so the finer level takes over
// there and the seam moves away from what the image shows.
import type { RegionOwners } from './regions.ts';
import { finerReachVoxels } from '../../raycast/seam-reach.ts';
import { NO_OWNER } from './regions.ts';

/** How many times at most a view is refined again where its rays found the surface (each an image more). */
export const MAX_GUIDED_PASSES = 4;

/** Voxels of the hit's level, before and after the hit along the ray, whose level-0 chunks count as seen. */
export const GUARD_VOXELS = 2;

/** A seen chunk no first hit lies in, only near one (a guard, a seam); 1 + n: n pixels' first hits lie in it. */
export const SEEN_NEAR = 1;

/** The pixels whose first hit lies in a chunk of mark `mark` (0 for a chunk not seen or only near a hit). */
export const seenPixels = (mark: number): number => (mark > SEEN_NEAR ? mark - SEEN_NEAR : 0);

export interface SeenLevel0 {
  dims: readonly [number, number, number];
  chunkEdge: number;
  chunkGrid: readonly [number, number, number];
}

/**
 * The seen level-0 chunks of `into` (a copy; all zero when absent) and of the
 * hits: `hits` x, y, z per hit in level-0 voxels, `dirs` each hit's ray's unit
 * direction in level-0 voxels; `regions` the step's region grid (which level
 * a hit is in: its guard; the seams), `scales[L]` level-0 voxels per voxel of L.
 * `added`: chunks not seen in `into`. Each chunk's mark is the larger of
 * `into`'s and this image's.
 */
export function seenChunks(
  hits: Float64Array,
  dirs: Float64Array,
  level0: SeenLevel0,
  regions: (Pick<RegionOwners, 'owner'> & { grid: readonly number[]; edge: readonly number[] }) | null,
  scales: readonly (readonly [number, number, number])[],
  into?: Uint32Array,
): { seen: Uint32Array; added: number } {
  const [gx, gy, gz] = level0.chunkGrid;
  const [dx, dy, dz] = level0.dims;
  const e = level0.chunkEdge;
  // this image's marks, then the larger of these and those seen before
  const now = new Uint32Array(gx * gy * gz);
  if (into && into.length !== now.length) throw new RangeError(`seenChunks: ${into.length} chunks seen before, level 0 has ${now.length}`);
  const mark = (x: number, y: number, z: number, hit: boolean) => {
    if (!(x >= 0 && y >= 0 && z >= 0 && x < dx && y < dy && z < dz)) return;
    const c = Math.floor(x / e) + gx * (Math.floor(y / e) + gy * Math.floor(z / e));
    now[c] = hit ? Math.max(now[c], SEEN_NEAR) + 1 : Math.max(now[c], SEEN_NEAR);
  };
  const ownerOf = (qx: number, qy: number, qz: number): number => {
    if (!regions) return 0;
    const [rx, ry, rz] = regions.grid;
    if (qx < 0 || qy < 0 || qz < 0 || qx >= rx || qy >= ry || qz >= rz) return NO_OWNER;
    return regions.owner[qx + rx * (qy + ry * qz)];
  };
  const q = [0, 0, 0];
  const above = [0, 0, 0];
  /** Marks the chunks just above the seams of the hit's region within reach of a coarser level owning the region above. */
  const markAboveSeams = (p: readonly number[], own: number): void => {
    if (!regions) return;
    for (let k = 1; k < 8; k++) {
      for (let a = 0; a < 3; a++) above[a] = q[a] + ((k >> a) & 1);
      const P = ownerOf(above[0], above[1], above[2]);
      if (P === NO_OWNER || !(P > own)) continue;
      const s = scales[P] ?? [1, 1, 1];
      let near = true;
      for (let a = 0; a < 3 && near; a++) if ((k >> a) & 1) near = above[a] * regions.edge[a] - p[a] <= finerReachVoxels(s[a]);
      if (!near) continue;
      const at = [0, 1, 2].map((a) => ((k >> a) & 1 ? above[a] * regions.edge[a] + 0.5 : p[a]));
      mark(at[0], at[1], at[2], false);
    }
  };
  for (let i = 0; i + 2 < hits.length; i += 3) {
    const x = hits[i];
    const y = hits[i + 1];
    const z = hits[i + 2];
    if (!(Number.isFinite(x) && Number.isFinite(y) && Number.isFinite(z))) continue;
    let own = 0;
    if (regions) {
      for (let a = 0; a < 3; a++) q[a] = Math.floor(hits[i + a] / regions.edge[a]);
      const o = ownerOf(q[0], q[1], q[2]);
      own = o === NO_OWNER ? 0 : o;
    }
    const s = scales[own] ?? [1, 1, 1];
    const guard = GUARD_VOXELS * Math.max(s[0], s[1], s[2]);
    mark(x, y, z, true);
    markAboveSeams([x, y, z], own);
    for (const g of [-guard, guard]) mark(x + g * dirs[i], y + g * dirs[i + 1], z + g * dirs[i + 2], false);
  }
  let added = 0;
  for (let c = 0; c < now.length; c++) {
    const before = into?.[c] ?? 0;
    if (before === 0 && now[c] > 0) added++;
    if (before > now[c]) now[c] = before;
  }
  return { seen: now, added };
}

/**
 * Each covered pixel's first hit in level-0 voxels (x, y, z) and its ray's
 * unit direction there, from an image's depth (`size` pixels, rows top to
 * bottom, WebGPU depth in [0, 1], 1 where nothing was hit): `inverseViewProj`
 * (column-major) takes clip space to the world, where level-0 voxel v lies at
 * (v + origin) * voxelSize, and `eye` is the camera in the world.
 */
export function hitsFromDepth(
  depth: Float32Array,
  [width, height]: readonly [number, number],
  inverseViewProj: ArrayLike<number>,
  eye: ArrayLike<number>,
  voxelSize: readonly number[],
  origin: readonly number[],
): { hits: Float64Array; dirs: Float64Array } {
  const m = inverseViewProj;
  const e = [0, 1, 2].map((a) => eye[a] / voxelSize[a] - origin[a]);
  let covered = 0;
  for (let i = 0; i < width * height; i++) if (depth[i] < 1) covered++;
  const hits = new Float64Array(3 * covered);
  const dirs = new Float64Array(3 * covered);
  let k = 0;
  for (let y = 0; y < height; y++)
    for (let x = 0; x < width; x++) {
      const z = depth[y * width + x];
      if (!(z < 1)) continue;
      const nx = ((x + 0.5) / width) * 2 - 1;
      const ny = 1 - ((y + 0.5) / height) * 2;
      const w = m[3] * nx + m[7] * ny + m[11] * z + m[15];
      let len = 0;
      for (let a = 0; a < 3; a++) {
        const world = (m[a] * nx + m[4 + a] * ny + m[8 + a] * z + m[12 + a]) / w;
        hits[k + a] = world / voxelSize[a] - origin[a];
        dirs[k + a] = hits[k + a] - e[a];
        len += dirs[k + a] * dirs[k + a];
      }
      len = Math.sqrt(len) || 1;
      for (let a = 0; a < 3; a++) dirs[k + a] /= len;
      k += 3;
    }
  return { hits, dirs };
}
