// The geometry of the clip's handles (src/app/clip-drag.ts draws and drags
// them): where the box's face handles and the plane's centre and rotation
// knob are, which one is under the pointer (in screen pixels), and how a
// drag moves the plane. The plane is handled in world space (voxel + origin)
// times the voxel size, so its knob stands at right angles to it on screen
// whatever the voxel size; the clip keeps it in level-0 voxels.
import type { ClipBox, ClipPlane } from './clip.ts';

type Vec3 = readonly [number, number, number] | readonly number[];

/** The centre of face (axis, side) of a box: side 0 the lower face, 1 the upper (box order x0,y0,z0,x1,y1,z1). */
export function boxFaceCentre(box: ClipBox, axis: number, side: 0 | 1): [number, number, number] {
  const p: [number, number, number] = [(box[0] + box[3]) / 2, (box[1] + box[4]) / 2, (box[2] + box[5]) / 2];
  p[axis] = box[axis + 3 * side];
  return p;
}

/**
 * World position -> canvas pixels (x right, y down, from the top left) through
 * `viewProj` (column-major, gl-matrix's); false when the point is behind the
 * eye (it has no place on screen). Allocates nothing.
 */
export function projectToPixels(viewProj: ArrayLike<number>, p: Vec3, width: number, height: number, out: number[]): boolean {
  const m = viewProj;
  const x = m[0] * p[0] + m[4] * p[1] + m[8] * p[2] + m[12];
  const y = m[1] * p[0] + m[5] * p[1] + m[9] * p[2] + m[13];
  const w = m[3] * p[0] + m[7] * p[1] + m[11] * p[2] + m[15];
  if (!(w > 0)) return false;
  out[0] = ((x / w + 1) / 2) * width;
  out[1] = ((1 - y / w) / 2) * height;
  return true;
}

/**
 * The handle nearest to (x, y) within `radius` pixels: `xy` holds the
 * handles' pixel positions in pairs (NaN for one not on screen); -1 when none
 * is that close. Ties go to the first.
 */
export function nearestHandle(xy: ArrayLike<number>, count: number, x: number, y: number, radius: number): number {
  let best = -1,
    bestD = radius * radius;
  for (let i = 0; i < count; i++) {
    const dx = xy[2 * i] - x,
      dy = xy[2 * i + 1] - y;
    const d = dx * dx + dy * dy;
    if (d < bestD || (best < 0 && d === bestD)) {
      best = i;
      bestD = d;
    }
  }
  return best;
}

/**
 * Along the line p + s e (e a unit vector): the s of the point nearest the
 * ray o + t d; NaN when the two are parallel (seen end on, the line gives the
 * pointer no direction to follow).
 */
export function nearestOnLine(p: Vec3, e: Vec3, o: Vec3, d: Vec3): number {
  // minimise |p + s e - o - t d|: s = (b (d.w) - c (e.w)) / (c - b^2), w = p - o, b = e.d, c = d.d
  const w0 = p[0] - o[0],
    w1 = p[1] - o[1],
    w2 = p[2] - o[2];
  const b = e[0] * d[0] + e[1] * d[1] + e[2] * d[2];
  const c = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  const dw = d[0] * w0 + d[1] * w1 + d[2] * w2;
  const ew = e[0] * w0 + e[1] * w1 + e[2] * w2;
  const den = c - b * b;
  return den <= 1e-9 * c ? Number.NaN : (b * dw - c * ew) / den;
}

/**
 * Where the rotation knob goes for a pointer ray (o, d): the point of the
 * sphere (centre c, radius r) that the ray meets, on its near side
 * (`far` false: the knob faces the eye) or far side; where the ray misses
 * the sphere, the sphere's point nearest the ray. The unit direction from c,
 * i.e. the plane's new normal; null for a ray through c's own direction
 * undefined (d zero).
 */
export function knobDirection(c: Vec3, r: number, o: Vec3, d: Vec3, far: boolean): [number, number, number] | null {
  const dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  if (!(dd > 0)) return null;
  const w = [o[0] - c[0], o[1] - c[1], o[2] - c[2]];
  // |w + t d|^2 = r^2: t = (-b +- sqrt(b^2 - dd (ww - r^2))) / dd, b = w.d
  const b = w[0] * d[0] + w[1] * d[1] + w[2] * d[2];
  const disc = b * b - dd * (w[0] * w[0] + w[1] * w[1] + w[2] * w[2] - r * r);
  const t = (-b + (disc > 0 ? (far ? 1 : -1) * Math.sqrt(disc) : 0)) / dd;
  const q = [w[0] + t * d[0], w[1] + t * d[1], w[2] + t * d[2]];
  const len = Math.hypot(q[0], q[1], q[2]);
  return len > 0 ? [q[0] / len, q[1] / len, q[2] / len] : null;
}

/** Whether a knob at c + r n is on the far side of the sphere seen along the ray direction d (from the eye). */
export function knobIsFar(n: Vec3, d: Vec3): boolean {
  return n[0] * d[0] + n[1] * d[1] + n[2] * d[2] > 0;
}

/** A plane in world units: unit normal, and n . x >= d kept. */
export interface WorldPlane {
  normal: [number, number, number];
  d: number;
}

/** A clip plane (level-0 voxels) in world units: x_world = (x + origin) * voxelSize. */
export function planeToWorld(plane: ClipPlane, voxelSize: Vec3, origin: Vec3): WorldPlane {
  // n . x >= d with x = w / s - o: (n / s) . w >= d + n . o
  const n = plane.normal;
  const m = [n[0] / voxelSize[0], n[1] / voxelSize[1], n[2] / voxelSize[2]];
  const len = Math.hypot(m[0], m[1], m[2]);
  return { normal: [m[0] / len, m[1] / len, m[2] / len], d: (plane.d + n[0] * origin[0] + n[1] * origin[1] + n[2] * origin[2]) / len };
}

/** The plane through world point `p` with world normal `nw`, as a clip plane in level-0 voxels with a unit normal. */
export function planeFromWorld(nw: Vec3, p: Vec3, voxelSize: Vec3, origin: Vec3): ClipPlane {
  // nw . w >= nw . p with w = (x + o) * s: (nw * s) . x >= nw . p - (nw * s) . o
  const m = [nw[0] * voxelSize[0], nw[1] * voxelSize[1], nw[2] * voxelSize[2]];
  const len = Math.hypot(m[0], m[1], m[2]);
  const d = nw[0] * p[0] + nw[1] * p[1] + nw[2] * p[2] - (m[0] * origin[0] + m[1] * origin[1] + m[2] * origin[2]);
  return { normal: [m[0] / len, m[1] / len, m[2] / len], d: d / len };
}

/**
 * The plane's centre handle (level-0 voxels): `previous` moved onto the plane
 * along its normal while that stays inside `lo`..`hi` (so the handle the
 * user placed stays put as the plane moves), else the centre of the plane's
 * polygon in the box (its corners' mean), else the box's centre moved onto
 * the plane.
 */
export function planeCentre(
  plane: ClipPlane,
  polygon: readonly (readonly number[])[],
  lo: Vec3,
  hi: Vec3,
  previous?: Vec3,
): [number, number, number] {
  const n = plane.normal;
  const nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
  const onPlane = (p: Vec3): [number, number, number] => {
    const k = (plane.d - (n[0] * p[0] + n[1] * p[1] + n[2] * p[2])) / nn;
    return [p[0] + k * n[0], p[1] + k * n[1], p[2] + k * n[2]];
  };
  if (previous) {
    const p = onPlane(previous);
    if ([0, 1, 2].every((a) => p[a] >= lo[a] - 1e-6 && p[a] <= hi[a] + 1e-6)) return p;
  }
  if (polygon.length > 0) {
    const c: [number, number, number] = [0, 0, 0];
    for (const q of polygon) for (let a = 0; a < 3; a++) c[a] += q[a] / polygon.length;
    return c;
  }
  return onPlane([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2]);
}
