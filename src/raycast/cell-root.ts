// The exact first crossing of a ray with the trilinear interpolant of one cell
// (Marmitt, Kleer, Wald, Friedrich, Slusallek, "Fast and Accurate Ray-Voxel
// Intersection Techniques for Iso-Surface Ray Tracing", VMV 2004): the CPU
// twin of shaders/raycast/cell_root.wgsl, function for function (camelCase
// names: cell_first_crossing is cellFirstCrossing), for the tests, CPU picking
// and the CLI. It computes in double precision where the shader has f32; the
// algorithm, the constants and the degenerate cases are the same.
//
// Conventions: a cell's 8 corner values v[x + 2y + 4z] (c000, c100, c010,
// c110, c001, c101, c011, c111: x fastest), cell-local coordinates in the
// unit cube, the trilinear interpolant
//   f(p) = sum over corners of v[i] * (x or 1-x) * (y or 1-y) * (z or 1-z),
// a ray p(t) = origin + t * dir, and [t0, t1] the ray's parameter interval
// inside the cell (t0 >= 0: the sentinel CELL_ROOT_NONE is negative).
//
// How: with s = (t - t0) / (t1 - t0) in [0, 1], q = origin + t0 * dir (the
// entry) and D = (t1 - t0) * dir (entry to exit), f(q + s D) - iso is a cubic
// g(s) = a s^3 + b s^2 + c s + e. The corner values are first shifted by iso
// and divided by their largest magnitude, so every coefficient is O(1) for
// tiny and huge data alike (the root does not change). The coefficients are
// the Taylor terms at the entry, each computed from corner differences
// (no expansion of large monomials, no cancellation beyond the data's own):
//   e = f(q)                   (trilinear by lerps)
//   c = grad f(q) . D          (bilinear lerps of the edge differences)
//   b = f_xy(q) Dx Dy + f_xz(q) Dx Dz + f_yz(q) Dy Dz   (face "twists", lerped)
//   a = k Dx Dy Dz, k = the cell's trilinear (xyz) coefficient
// g' = 3a s^2 + 2b s + c has at most two roots; they split [0, 1] into at most
// three pieces on each of which g is monotonic. The first piece whose ends
// differ in sign, or has an end where g == 0, holds the first crossing; a
// safeguarded Newton iteration (bisection whenever Newton leaves the bracket
// or stops halving it, Numerical Recipes' rtsafe) refines it to ~1e-7 of the
// cell's chord, at most CELL_ROOT_MAX_STEPS steps.
//
// Degenerate cases: f identically equal to iso (all corners equal iso) is a
// hit at t0; dir == 0 or t0 == t1 is a hit at t0 only when f(entry) == iso;
// a, b, c near or equal to zero need no threshold (the stable quadratic
// formula gives the split points, an exact zero skips them). A tangential
// touch counts as a hit when g is exactly 0 at a piece's end (the touch point
// is a split point). A double root that does not change sign, with g not
// exactly 0 at its split point, is MISSED (as is a near-touch; and rounding
// may turn a near-touch into a hit): such rays graze the surface, and the
// next cell or pixel carries the silhouette.

/** A point or direction in cell-local coordinates. */
export type CellVec3 = readonly [number, number, number];

/** What cellFirstCrossing returns when the ray does not cross the surface in [t0, t1]. */
export const CELL_ROOT_NONE = -1;
export const CELL_ROOT_MAX_STEPS = 32;
/** Stop when a step is below this (in s, the fraction of the chord): ~f32's resolution on [0, 1]. */
export const CELL_ROOT_TOLERANCE = 1e-7;

/** g(s) = ((a s + b) s + c) s + e on s in [0, 1]. */
export interface CellCubic {
  a: number;
  b: number;
  c: number;
  e: number;
}

/** (1 - t) a + t b: exact at both ends (t = 0 gives a, t = 1 gives b). */
export function cellLerp(a: number, b: number, t: number): number {
  return (1 - t) * a + t * b;
}

/** The trilinear interpolant at p (cell-local; outside the cube it extends the polynomial). */
export function cellTrilinear(v: ArrayLike<number>, p: CellVec3): number {
  const y0 = cellLerp(cellLerp(v[0], v[1], p[0]), cellLerp(v[2], v[3], p[0]), p[1]);
  const y1 = cellLerp(cellLerp(v[4], v[5], p[0]), cellLerp(v[6], v[7], p[0]), p[1]);
  return cellLerp(y0, y1, p[2]);
}

/**
 * Its gradient at p, in value per cell edge: each component is the bilinear
 * interpolation, over the two other axes, of the four edge differences along it.
 */
export function cellGradient(v: ArrayLike<number>, p: CellVec3): [number, number, number] {
  const gx = cellLerp(cellLerp(v[1] - v[0], v[3] - v[2], p[1]), cellLerp(v[5] - v[4], v[7] - v[6], p[1]), p[2]);
  const gy = cellLerp(cellLerp(v[2] - v[0], v[3] - v[1], p[0]), cellLerp(v[6] - v[4], v[7] - v[5], p[0]), p[2]);
  const gz = cellLerp(cellLerp(v[4] - v[0], v[5] - v[1], p[0]), cellLerp(v[6] - v[2], v[7] - v[3], p[0]), p[1]);
  return [gx, gy, gz];
}

/** The cubic g(s) = f(q + s dir) for s in [0, 1] (v already shifted by iso). */
export function cellCubic(v: ArrayLike<number>, q: CellVec3, dir: CellVec3): CellCubic {
  // The twist of each face pair (the mixed second derivative), lerped across.
  const fxy = cellLerp(v[3] - v[2] - v[1] + v[0], v[7] - v[6] - v[5] + v[4], q[2]);
  const fxz = cellLerp(v[5] - v[4] - v[1] + v[0], v[7] - v[6] - v[3] + v[2], q[1]);
  const fyz = cellLerp(v[6] - v[4] - v[2] + v[0], v[7] - v[5] - v[3] + v[1], q[0]);
  const k = v[7] - v[6] - v[5] + v[4] - (v[3] - v[2] - v[1] + v[0]);
  const g = cellGradient(v, q);
  return {
    a: k * dir[0] * dir[1] * dir[2],
    b: fxy * dir[0] * dir[1] + fxz * dir[0] * dir[2] + fyz * dir[1] * dir[2],
    c: g[0] * dir[0] + g[1] * dir[1] + g[2] * dir[2],
    e: cellTrilinear(v, q),
  };
}

export function cellCubicValue(k: CellCubic, s: number): number {
  return ((k.a * s + k.b) * s + k.c) * s + k.e;
}

export function cellCubicSlope(k: CellCubic, s: number): number {
  return (3 * k.a * s + 2 * k.b) * s + k.c;
}

/**
 * The root in [lo, hi] where g(lo) = glo and g(hi) = ghi have opposite signs
 * (neither zero) and g is monotonic: safeguarded Newton (rtsafe).
 */
export function cellCubicRefine(k: CellCubic, loIn: number, hiIn: number, glo: number, ghi: number): number {
  let lo = loIn; // g has the sign of glo here
  let hi = hiIn; // and the other sign here
  const loNegative = glo < 0;
  // Start from the secant (regula falsi) point.
  let x = lo + (hi - lo) * (glo / (glo - ghi));
  if (!(x > lo && x < hi)) x = 0.5 * (lo + hi);
  let stepOld = hi - lo;
  let step = stepOld;
  for (let i = 0; i < CELL_ROOT_MAX_STEPS; i++) {
    const gx = cellCubicValue(k, x);
    if (gx === 0) return x;
    if (gx < 0 === loNegative) lo = x;
    else hi = x;
    const slope = cellCubicSlope(k, x);
    const newtonStep = gx / (slope !== 0 ? slope : 1);
    const newton = x - newtonStep;
    stepOld = step;
    if (slope === 0 || !(newton > lo && newton < hi) || Math.abs(2 * gx) > Math.abs(stepOld * slope)) {
      step = 0.5 * (hi - lo);
      x = lo + step;
    } else {
      step = newtonStep;
      x = newton;
    }
    if (Math.abs(step) <= CELL_ROOT_TOLERANCE) break;
  }
  return Math.min(Math.max(x, lo), hi);
}

/** The root of g on the piece [lo, hi] (g monotonic there), or CELL_ROOT_NONE. */
export function cellCubicPieceRoot(k: CellCubic, lo: number, hi: number): number {
  const glo = cellCubicValue(k, lo);
  if (glo === 0) return lo;
  const ghi = cellCubicValue(k, hi);
  if (ghi === 0) return hi;
  if (glo < 0 === ghi < 0) return CELL_ROOT_NONE;
  return cellCubicRefine(k, lo, hi, glo, ghi);
}

/** The smallest s in [0, 1] with g(s) == 0, or CELL_ROOT_NONE. */
export function cellCubicFirstRoot(k: CellCubic): number {
  // Split points: the roots of g'(s) = qa s^2 + qb s + qc, by the stable
  // formula (no cancellation; qa == 0 leaves the linear root qc / q = -qc / qb).
  const qa = 3 * k.a;
  const qb = 2 * k.b;
  const qc = k.c;
  let r1 = 1;
  let r2 = 1;
  const disc = qb * qb - 4 * qa * qc;
  if (disc >= 0) {
    const q = -0.5 * (qb + (qb >= 0 ? 1 : -1) * Math.sqrt(disc));
    if (q !== 0) {
      r1 = Math.min(Math.max(qc / q, 0), 1);
      if (qa !== 0) r2 = Math.min(Math.max(q / qa, 0), 1);
    }
  }
  // Pieces [0, s1], [s1, s2], [s2, 1] (empty ones cost an evaluation, no more).
  const ends = [0, Math.min(r1, r2), Math.max(r1, r2), 1];
  for (let i = 0; i < 3; i++) {
    const r = cellCubicPieceRoot(k, ends[i], ends[i + 1]);
    if (r >= 0) return r;
  }
  return CELL_ROOT_NONE;
}

/**
 * The smallest t in [t0, t1] where the trilinear interpolant of the cell
 * (corners v, x fastest) along origin + t dir equals iso, or CELL_ROOT_NONE.
 */
export function cellFirstCrossing(v: ArrayLike<number>, iso: number, origin: CellVec3, dir: CellVec3, t0: number, t1: number): number {
  if (!(t1 >= t0)) return CELL_ROOT_NONE;
  // Shift by iso and scale by the largest magnitude: values in [-1, 1].
  const w = new Array<number>(8);
  let m = 0;
  for (let i = 0; i < 8; i++) {
    w[i] = v[i] - iso;
    m = Math.max(m, Math.abs(w[i]));
  }
  if (m === 0) return t0; // the whole cell is on the surface
  for (let i = 0; i < 8; i++) w[i] = w[i] / m;
  const chord = t1 - t0;
  const q: CellVec3 = [origin[0] + t0 * dir[0], origin[1] + t0 * dir[1], origin[2] + t0 * dir[2]];
  const k = cellCubic(w, q, [chord * dir[0], chord * dir[1], chord * dir[2]]);
  const s = cellCubicFirstRoot(k);
  if (s < 0) return CELL_ROOT_NONE;
  return Math.min(t0 + s * chord, t1);
}
