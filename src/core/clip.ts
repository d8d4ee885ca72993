// Cutting a surface open: a clip box and one free plane, in level-0 voxel
// index coordinates (voxel (i, j, k) at (i, j, k)); what is kept is inside
// the box and on the plane's positive side (n . x >= d).
//
// The box keeps whole marching-cubes cells: a triangle is kept when its cell
// (the one holding its centroid) lies in the box, so a box whose corners are
// grid points gives exactly the surface of the sub-volume (VTK's
// vtkExtractVOI then vtkMarchingCubes). The plane cuts triangles (as
// vtkClipPolyData): the part on its positive side is kept, split where the
// plane crosses. The renderer does the same per fragment (shaders/render/
// surface.wgsl), and a stream leaves out chunks the clip removes whole.

export type ClipBox = readonly [number, number, number, number, number, number];

export interface ClipPlane {
  /** Need not be unit length; (0, 0, 0) is refused. */
  normal: readonly [number, number, number];
  d: number;
}

export interface Clip {
  box?: ClipBox;
  plane?: ClipPlane;
}

/** 'x0,y0,z0,x1,y1,z1' -> a box, or why not. `whole`: the volume's box (level-0 grid points), which the clip must meet. */
export function parseClipBox(text: string, dims?: readonly number[]): ClipBox | string {
  const v = text.split(',').map((s) => (s.trim() === '' ? Number.NaN : Number(s)));
  if (v.length !== 6 || !v.every(Number.isFinite)) return 'six numbers x0,y0,z0,x1,y1,z1';
  if (!(v[0] < v[3] && v[1] < v[4] && v[2] < v[5])) return 'each lower corner coordinate must be below the upper one';
  if (dims && [0, 1, 2].some((a) => v[a + 3] <= 0 || v[a] >= dims[a] - 1))
    return `the box holds no cell of the volume (0..${dims.map((n) => n - 1).join(', 0..')})`;
  return v as unknown as ClipBox;
}

/** 'nx,ny,nz,d' -> a plane (keeps n . x >= d), or why not. */
export function parseClipPlane(text: string): ClipPlane | string {
  const v = text.split(',').map((s) => (s.trim() === '' ? Number.NaN : Number(s)));
  if (v.length !== 4 || !v.every(Number.isFinite)) return 'four numbers nx,ny,nz,d (keeps nx*x + ny*y + nz*z >= d)';
  if (v[0] === 0 && v[1] === 0 && v[2] === 0) return 'the normal (nx, ny, nz) is zero: a plane needs a direction';
  return { normal: [v[0], v[1], v[2]], d: v[3] };
}

/** Whether a clip removes nothing. */
export function clipIsEmpty(clip: Clip | undefined): boolean {
  return !clip || (!clip.box && !clip.plane);
}

/**
 * The part of an indexed mesh (level-0 voxel coordinates) the clip keeps: the
 * box's whole cells, then the plane's positive side with crossing triangles
 * split (new vertices where edges cross the plane, shared by both triangles
 * of an edge).
 */
export function clipMesh(positions: Float32Array, indices: Uint32Array, clip: Clip): { positions: Float32Array; indices: Uint32Array } {
  let kept = indices;
  if (clip.box) {
    const [x0, y0, z0, x1, y1, z1] = clip.box;
    const out: number[] = [];
    for (let t = 0; t < indices.length; t += 3) {
      const a = 3 * indices[t],
        b = 3 * indices[t + 1],
        c = 3 * indices[t + 2];
      // the cell holding the centroid: inside the box when its lower corner is in [lo, hi - 1]
      const cx = Math.floor((positions[a] + positions[b] + positions[c]) / 3);
      const cy = Math.floor((positions[a + 1] + positions[b + 1] + positions[c + 1]) / 3);
      const cz = Math.floor((positions[a + 2] + positions[b + 2] + positions[c + 2]) / 3);
      if (cx >= x0 && cx + 1 <= x1 && cy >= y0 && cy + 1 <= y1 && cz >= z0 && cz + 1 <= z1)
        out.push(indices[t], indices[t + 1], indices[t + 2]);
    }
    kept = Uint32Array.from(out);
  }
  if (!clip.plane) return { positions, indices: kept };
  const [nx, ny, nz] = clip.plane.normal;
  const d = clip.plane.d;
  const side = (v: number) => nx * positions[3 * v] + ny * positions[3 * v + 1] + nz * positions[3 * v + 2] - d;
  const extra: number[] = [];
  const crossings = new Map<string, number>();
  const base = positions.length / 3;
  /** The vertex where edge (a, b) crosses the plane, made once per edge. */
  const cross = (a: number, b: number, sa: number, sb: number): number => {
    const key = a < b ? `${a},${b}` : `${b},${a}`;
    let v = crossings.get(key);
    if (v === undefined) {
      const [p, q, sp, sq] = a < b ? [a, b, sa, sb] : [b, a, sb, sa];
      const t = sp / (sp - sq);
      for (let k = 0; k < 3; k++) extra.push(positions[3 * p + k] + t * (positions[3 * q + k] - positions[3 * p + k]));
      v = base + extra.length / 3 - 1;
      crossings.set(key, v);
    }
    return v;
  };
  const out: number[] = [];
  const tri = [0, 0, 0];
  const s = [0, 0, 0];
  for (let t = 0; t < kept.length; t += 3) {
    let inside = 0;
    for (let k = 0; k < 3; k++) {
      tri[k] = kept[t + k];
      s[k] = side(tri[k]);
      if (s[k] >= 0) inside++;
    }
    if (inside === 3) out.push(tri[0], tri[1], tri[2]);
    if (inside === 0 || inside === 3) continue;
    // rotate so the corners keep their winding: the odd one out first
    const odd = inside === 1 ? s.findIndex((x) => x >= 0) : s.findIndex((x) => x < 0);
    const a = tri[odd],
      b = tri[(odd + 1) % 3],
      c = tri[(odd + 2) % 3];
    const sa = s[odd],
      sb = s[(odd + 1) % 3],
      sc = s[(odd + 2) % 3];
    const ab = cross(a, b, sa, sb);
    const ca = cross(c, a, sc, sa);
    if (inside === 1) out.push(a, ab, ca);
    else out.push(ab, b, c, ab, c, ca);
  }
  const all = new Float32Array(positions.length + extra.length);
  all.set(positions);
  all.set(extra, positions.length);
  return { positions: all, indices: Uint32Array.from(out) };
}

/**
 * Whether the clip removes every cell of a region (level-0 voxels [lo, hi]
 * on each axis, hi the region's last grid point): a chunk so clipped is
 * neither fetched nor drawn.
 */
export function regionClipped(lo: readonly number[], hi: readonly number[], clip: Clip | undefined): boolean {
  if (!clip) return false;
  if (clip.box) {
    const b = clip.box;
    for (let a = 0; a < 3; a++) if (hi[a] <= b[a] || lo[a] >= b[a + 3]) return true;
  }
  if (clip.plane) {
    // the region's corner farthest along the normal is still behind the plane
    const n = clip.plane.normal;
    let best = 0;
    for (let a = 0; a < 3; a++) best += n[a] * (n[a] >= 0 ? hi[a] : lo[a]);
    if (best < clip.plane.d) return true;
  }
  return false;
}

/** The clip's planes as (n, -d) rows with n . x - d >= 0 inside: the box's six, then the free one. */
export function clipPlanes(clip: Clip | undefined): [number, number, number, number][] {
  const planes: [number, number, number, number][] = [];
  if (clip?.box) {
    const b = clip.box;
    planes.push([1, 0, 0, -b[0]], [0, 1, 0, -b[1]], [0, 0, 1, -b[2]], [-1, 0, 0, b[3]], [0, -1, 0, b[4]], [0, 0, -1, b[5]]);
  }
  if (clip?.plane) planes.push([...clip.plane.normal, -clip.plane.d] as [number, number, number, number]);
  return planes;
}

/**
 * The caps of a clip: per plane of the clip, the convex polygon where it
 * cuts the volume's box [0, dims - 1] and every other plane keeps it (level-0
 * voxel coordinates, corners in order around the polygon). Empty planes
 * (outside the box or cut away by the others) are left out.
 */
export function capPolygons(
  clip: Clip | undefined,
  dims: readonly number[],
): { plane: [number, number, number, number]; corners: number[][] }[] {
  const planes = clipPlanes(clip);
  const box = [0, 1, 2].map((a) => Math.max(0, dims[a] - 1));
  const out: { plane: [number, number, number, number]; corners: number[][] }[] = [];
  planes.forEach((plane, i) => {
    let poly = planeInBox(plane, box);
    for (let j = 0; j < planes.length && poly.length >= 3; j++) if (j !== i) poly = keepSide(poly, planes[j]);
    if (poly.length >= 3) out.push({ plane, corners: poly });
  });
  return out;
}

/** The free plane's polygon (capPolygons): where it meets the volume's box and the clip box; empty when it misses them. */
export function freePlanePolygon(clip: Clip | undefined, dims: readonly number[]): number[][] {
  if (!clip?.plane) return [];
  const last = capPolygons(clip, dims).at(-1);
  // the free plane is the last of clipPlanes; a box face's polygon is last when the plane's was left out
  return last && samePlane(last.plane, clip.plane) ? last.corners : [];
}

function samePlane(row: readonly number[], plane: ClipPlane): boolean {
  return row[0] === plane.normal[0] && row[1] === plane.normal[1] && row[2] === plane.normal[2] && row[3] === -plane.d;
}

/** The polygon where n . x + w = 0 cuts the box [0, hi]: its crossings of the 12 edges, in order around their centre. */
function planeInBox(plane: readonly number[], hi: readonly number[]): number[][] {
  const [nx, ny, nz, w] = plane;
  const f = (p: readonly number[]) => nx * p[0] + ny * p[1] + nz * p[2] + w;
  const corners = [0, 1, 2, 3, 4, 5, 6, 7].map((k) => [k & 1 ? hi[0] : 0, k & 2 ? hi[1] : 0, k & 4 ? hi[2] : 0]);
  const points: number[][] = [];
  for (let a = 0; a < 8; a++) {
    for (const bit of [1, 2, 4]) {
      if (a & bit) continue;
      const p = corners[a],
        q = corners[a | bit];
      const fp = f(p),
        fq = f(q);
      if (fp === 0) points.push(p);
      if ((fp < 0 && fq > 0) || (fp > 0 && fq < 0)) {
        const t = fp / (fp - fq);
        points.push(p.map((v, k) => v + t * (q[k] - v)));
      }
    }
  }
  const unique = points.filter((p, i) => points.findIndex((q) => q.every((v, k) => Math.abs(v - p[k]) < 1e-9)) === i);
  if (unique.length < 3) return [];
  // order around the centre, in the plane's own axes
  const c = [0, 1, 2].map((k) => unique.reduce((s, p) => s + p[k], 0) / unique.length);
  const n = [nx, ny, nz];
  const u = Math.abs(n[0]) < 0.9 ? cross(n, [1, 0, 0]) : cross(n, [0, 1, 0]);
  const v = cross(n, u);
  const angle = (p: number[]) => Math.atan2(dot(sub(p, c), v), dot(sub(p, c), u));
  return unique.sort((a, b) => angle(a) - angle(b));
}

/** Sutherland-Hodgman: the part of a convex polygon with n . x + w >= 0. */
function keepSide(poly: number[][], plane: readonly number[]): number[][] {
  const f = (p: number[]) => plane[0] * p[0] + plane[1] * p[1] + plane[2] * p[2] + plane[3];
  const out: number[][] = [];
  for (let i = 0; i < poly.length; i++) {
    const p = poly[i],
      q = poly[(i + 1) % poly.length];
    const fp = f(p),
      fq = f(q);
    if (fp >= 0) out.push(p);
    if (fp >= 0 !== fq >= 0) {
      const t = fp / (fp - fq);
      out.push(p.map((v, k) => v + t * (q[k] - v)));
    }
  }
  return out;
}

const dot = (a: readonly number[], b: readonly number[]) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const sub = (a: readonly number[], b: readonly number[]) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const cross = (a: readonly number[], b: readonly number[]) => [
  a[1] * b[2] - a[2] * b[1],
  a[2] * b[0] - a[0] * b[2],
  a[0] * b[1] - a[1] * b[0],
];

/**
 * The 4^3 blocks whose voxels a trilinear sample on the caps can read: those
 * within one voxel of a cap polygon's plane, inside the polygon's bounds.
 * Sorted block ids (raster order over `blockGrid`).
 */
export function capBlocks(
  caps: { plane: readonly number[]; corners: number[][] }[],
  dims: readonly number[],
  /** Only blocks within these block-index ranges (inclusive; a store's resident chunks): the walk is sized by them, not the level. */
  within?: readonly { lo: readonly number[]; hi: readonly number[] }[],
): Uint32Array {
  const grid = dims.map((n) => Math.ceil(n / 4));
  const ids = new Set<number>();
  const ranges = within ?? [{ lo: [0, 0, 0], hi: grid.map((g) => g - 1) }];
  for (const cap of caps) for (const range of ranges) addCapBlocks(ids, cap, grid, range);
  return Uint32Array.from([...ids].sort((a, b) => a - b));
}

/** capBlocks for one cap within one block range. */
function addCapBlocks(
  ids: Set<number>,
  cap: { plane: readonly number[]; corners: number[][] },
  grid: readonly number[],
  range: { lo: readonly number[]; hi: readonly number[] },
): void {
  const [nx, ny, nz, w] = cap.plane;
  const lo = [0, 1, 2].map((a) => Math.max(range.lo[a], 0, Math.floor((Math.min(...cap.corners.map((p) => p[a])) - 1) / 4)));
  const hi = [0, 1, 2].map((a) => Math.min(range.hi[a], grid[a] - 1, Math.floor((Math.max(...cap.corners.map((p) => p[a])) + 1) / 4)));
  // a sample at x reads voxels within 1 of it on each axis: a block is needed when the plane meets its
  // voxels' box [4b, 4b + 3] grown by 1, centre 4b + 1.5, half-extent 2.5
  const reach = 2.5 * (Math.abs(nx) + Math.abs(ny) + Math.abs(nz));
  for (let bz = lo[2]; bz <= hi[2]; bz++) {
    for (let by = lo[1]; by <= hi[1]; by++) {
      for (let bx = lo[0]; bx <= hi[0]; bx++) {
        const distance = Math.abs(nx * (4 * bx + 1.5) + ny * (4 * by + 1.5) + nz * (4 * bz + 1.5) + w);
        if (distance <= reach) ids.add(bx + grid[0] * (by + grid[1] * bz));
      }
    }
  }
}

/**
 * Where a ray (level-0 voxels) first meets a box: the face's axis and side
 * (0 lower, 1 upper) and the point; null when it misses or starts inside.
 */
export function boxEntryFace(
  box: ClipBox,
  origin: readonly number[],
  dir: readonly number[],
): { axis: number; side: 0 | 1; point: [number, number, number] } | null {
  let tNear = -Infinity,
    tFar = Infinity,
    axis = -1,
    side: 0 | 1 = 0;
  for (let a = 0; a < 3; a++) {
    const lo = box[a],
      hi = box[a + 3];
    if (dir[a] === 0) {
      if (origin[a] < lo || origin[a] > hi) return null;
      continue;
    }
    let t0 = (lo - origin[a]) / dir[a],
      t1 = (hi - origin[a]) / dir[a];
    let s: 0 | 1 = 0;
    if (t0 > t1) {
      [t0, t1] = [t1, t0];
      s = 1;
    }
    if (t0 > tNear) {
      tNear = t0;
      axis = a;
      side = s;
    }
    tFar = Math.min(tFar, t1);
  }
  if (axis < 0 || tNear > tFar || tNear < 0) return null;
  return { axis, side, point: [0, 1, 2].map((k) => origin[k] + tNear * dir[k]) as [number, number, number] };
}

/** Along the line through `point` parallel to `axis`: the parameter of the point nearest to the ray (origin, dir). */
export function nearestOnAxis(point: readonly number[], axis: number, origin: readonly number[], dir: readonly number[]): number {
  // lines p + s e and o + t d: s = (b e' - c d') / (a c - b^2) with a = 1 (e a unit axis)
  const w = [point[0] - origin[0], point[1] - origin[1], point[2] - origin[2]];
  const b = dir[axis];
  const c = dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2];
  const dw = w[axis];
  const ew = dir[0] * w[0] + dir[1] * w[1] + dir[2] * w[2];
  const den = c - b * b;
  return den <= 1e-12 * c ? 0 : (b * ew - c * dw) / den;
}

/**
 * The clip in the voxels of a level whose voxel spans `scale` level-0
 * voxels and whose voxel (0, 0, 0) lies at `offset` (level-0 voxels): the
 * same cut, for that level's caps. A plane's normal is then scaled (not unit).
 */
export function clipInLevel(clip: Clip, scale: readonly number[], offset: readonly number[]): Clip {
  const out: Clip = {};
  if (clip.box) {
    const b = clip.box;
    out.box = [0, 1, 2, 3, 4, 5].map((i) => (b[i] - offset[i % 3]) / scale[i % 3]) as unknown as ClipBox;
  }
  if (clip.plane) {
    const n = clip.plane.normal;
    out.plane = {
      normal: [n[0] * scale[0], n[1] * scale[1], n[2] * scale[2]],
      d: clip.plane.d - (n[0] * offset[0] + n[1] * offset[1] + n[2] * offset[2]),
    };
  }
  return out;
}

/**
 * Whether a cap of the clip can lie in the region [lo, hi] (level-0
 * voxels): one of the clip's planes passes through it and the clip keeps
 * part of it (a chunk the caps read).
 */
export function regionOnCap(lo: readonly number[], hi: readonly number[], clip: Clip | undefined): boolean {
  if (!clip || regionClipped(lo, hi, clip)) return false;
  return clipPlanes(clip).some(([nx, ny, nz, w]) => {
    const n = [nx, ny, nz];
    let min = w;
    let max = w;
    for (let a = 0; a < 3; a++) {
      min += n[a] * (n[a] >= 0 ? lo[a] : hi[a]);
      max += n[a] * (n[a] >= 0 ? hi[a] : lo[a]);
    }
    return min <= 0 && max >= 0;
  });
}
