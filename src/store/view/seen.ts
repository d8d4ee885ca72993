// Where an image's rays found the surface, as a cut for rays asks for it
// (CutInput.seen, issue 46): per level-0 chunk, 1 where a first hit lies, or
// a point GUARD_VOXELS voxels of the hit's level before or after it along
// its ray. The hit of a coarse level is where the finer surface is to be
// found to within about a coarse voxel, in front of it or behind: the guard
// asks for the finer chunks on both sides, so that the next image's hit does
// not land in a chunk nobody asked for (it would be asked for by that image).
import type { RegionOwners } from './regions.ts';
import { NO_OWNER } from './regions.ts';

/** How many times at most a view is refined again where its rays found the surface (each an image more). */
export const MAX_GUIDED_PASSES = 4;

/** Voxels of the hit's level, before and after the hit along the ray, whose level-0 chunks count as seen. */
export const GUARD_VOXELS = 2;

export interface SeenLevel0 {
  dims: readonly [number, number, number];
  chunkEdge: number;
  chunkGrid: readonly [number, number, number];
}

/**
 * The seen level-0 chunks of `into` (a copy; all zero when absent) and of the
 * hits: `hits` x, y, z per hit in level-0 voxels, `dirs` each hit's ray's unit
 * direction in level-0 voxels; `regions` the step's region grid (which level
 * a hit is in: its guard), `scales[L]` level-0 voxels per voxel of L.
 * `added`: chunks not seen in `into`.
 */
export function seenChunks(
  hits: Float64Array,
  dirs: Float64Array,
  level0: SeenLevel0,
  regions: (Pick<RegionOwners, 'owner'> & { grid: readonly number[]; edge: readonly number[] }) | null,
  scales: readonly (readonly [number, number, number])[],
  into?: Uint8Array,
): { seen: Uint8Array; added: number } {
  const [gx, gy, gz] = level0.chunkGrid;
  const [dx, dy, dz] = level0.dims;
  const e = level0.chunkEdge;
  const seen = new Uint8Array(gx * gy * gz);
  if (into) {
    if (into.length !== seen.length) throw new RangeError(`seenChunks: ${into.length} chunks seen before, level 0 has ${seen.length}`);
    seen.set(into);
  }
  let added = 0;
  const mark = (x: number, y: number, z: number) => {
    if (!(x >= 0 && y >= 0 && z >= 0 && x < dx && y < dy && z < dz)) return;
    const c = Math.floor(x / e) + gx * (Math.floor(y / e) + gy * Math.floor(z / e));
    if (seen[c] === 0) {
      seen[c] = 1;
      added++;
    }
  };
  const levelAt = (x: number, y: number, z: number): number => {
    if (!regions) return 0;
    const [rx, ry, rz] = regions.grid;
    const q = [Math.floor(x / regions.edge[0]), Math.floor(y / regions.edge[1]), Math.floor(z / regions.edge[2])];
    if (q[0] < 0 || q[1] < 0 || q[2] < 0 || q[0] >= rx || q[1] >= ry || q[2] >= rz) return 0;
    const L = regions.owner[q[0] + rx * (q[1] + ry * q[2])];
    return L === NO_OWNER ? 0 : L;
  };
  for (let i = 0; i + 2 < hits.length; i += 3) {
    const x = hits[i];
    const y = hits[i + 1];
    const z = hits[i + 2];
    if (!(Number.isFinite(x) && Number.isFinite(y) && Number.isFinite(z))) continue;
    const s = scales[levelAt(x, y, z)] ?? [1, 1, 1];
    const guard = GUARD_VOXELS * Math.max(s[0], s[1], s[2]);
    mark(x, y, z);
    for (const g of [-guard, guard]) mark(x + g * dirs[i], y + g * dirs[i + 1], z + g * dirs[i + 2]);
  }
  return { seen, added };
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
