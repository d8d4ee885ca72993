// The exact first crossing of a ray with the trilinear interpolant of one cell
// (Marmitt, Kleer, Wald, Friedrich, Slusallek, "Fast and Accurate Ray-Voxel
// Intersection Techniques for Iso-Surface Ray Tracing", VMV 2004), for the
// ray caster of issue 46. A snippet: no bindings; kernels compose it in.
// Mirrored line for line by src/raycast/cell-root.ts (cellFirstCrossing,
// cellTrilinear, cellGradient, ...), which the tests hold against NumPy.
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
// exactly 0 at its split point in f32, is MISSED (as is a near-touch; and f32
// rounding may turn a near-touch into a hit): such rays graze the surface,
// and the next cell or pixel carries the silhouette.
// Corner differences must be finite in f32 (|v - iso| < 3.4e38), and ones
// below f32's normal range (1e-38) may be flushed to zero (a flat cell: hit at t0).

const CELL_ROOT_NONE: f32 = -1.0;
const CELL_ROOT_MAX_STEPS: i32 = 32;
// Stop when a step is below this (in s, the fraction of the chord): ~f32's
// resolution on [0, 1].
const CELL_ROOT_TOLERANCE: f32 = 1e-7;

// g(s) = ((a s + b) s + c) s + e on s in [0, 1].
struct CellCubic {
  a: f32,
  b: f32,
  c: f32,
  e: f32,
}

// (1 - t) a + t b: exact at both ends (t = 0 gives a, t = 1 gives b).
fn cell_lerp(a: f32, b: f32, t: f32) -> f32 {
  return (1.0 - t) * a + t * b;
}

// The trilinear interpolant at p (cell-local; outside the cube it extends the polynomial).
fn cell_trilinear(v: array<f32, 8>, p: vec3f) -> f32 {
  let y0 = cell_lerp(cell_lerp(v[0], v[1], p.x), cell_lerp(v[2], v[3], p.x), p.y);
  let y1 = cell_lerp(cell_lerp(v[4], v[5], p.x), cell_lerp(v[6], v[7], p.x), p.y);
  return cell_lerp(y0, y1, p.z);
}

// Its gradient at p, in value per cell edge: each component is the bilinear
// interpolation, over the two other axes, of the four edge differences along it.
fn cell_gradient(v: array<f32, 8>, p: vec3f) -> vec3f {
  let gx = cell_lerp(cell_lerp(v[1] - v[0], v[3] - v[2], p.y), cell_lerp(v[5] - v[4], v[7] - v[6], p.y), p.z);
  let gy = cell_lerp(cell_lerp(v[2] - v[0], v[3] - v[1], p.x), cell_lerp(v[6] - v[4], v[7] - v[5], p.x), p.z);
  let gz = cell_lerp(cell_lerp(v[4] - v[0], v[5] - v[1], p.x), cell_lerp(v[6] - v[2], v[7] - v[3], p.x), p.y);
  return vec3f(gx, gy, gz);
}

// The cubic g(s) = f(q + s dir) for s in [0, 1] (v already shifted by iso).
fn cell_cubic(v: array<f32, 8>, q: vec3f, dir: vec3f) -> CellCubic {
  // The twist of each face pair (the mixed second derivative), lerped across.
  let fxy = cell_lerp(v[3] - v[2] - v[1] + v[0], v[7] - v[6] - v[5] + v[4], q.z);
  let fxz = cell_lerp(v[5] - v[4] - v[1] + v[0], v[7] - v[6] - v[3] + v[2], q.y);
  let fyz = cell_lerp(v[6] - v[4] - v[2] + v[0], v[7] - v[5] - v[3] + v[1], q.x);
  let k = (v[7] - v[6] - v[5] + v[4]) - (v[3] - v[2] - v[1] + v[0]);
  let g = cell_gradient(v, q);
  return CellCubic(
    k * dir.x * dir.y * dir.z,
    fxy * dir.x * dir.y + fxz * dir.x * dir.z + fyz * dir.y * dir.z,
    dot(g, dir),
    cell_trilinear(v, q),
  );
}

fn cell_cubic_value(k: CellCubic, s: f32) -> f32 {
  return ((k.a * s + k.b) * s + k.c) * s + k.e;
}

fn cell_cubic_slope(k: CellCubic, s: f32) -> f32 {
  return (3.0 * k.a * s + 2.0 * k.b) * s + k.c;
}

// The root in [lo, hi] where g(lo) = glo and g(hi) = ghi have opposite signs
// (neither zero) and g is monotonic: safeguarded Newton (rtsafe).
fn cell_cubic_refine(k: CellCubic, lo_in: f32, hi_in: f32, glo: f32, ghi: f32) -> f32 {
  var lo = lo_in; // g has the sign of glo here
  var hi = hi_in; // and the other sign here
  let lo_negative = glo < 0.0;
  // Start from the secant (regula falsi) point.
  var x = lo + (hi - lo) * (glo / (glo - ghi));
  if (!(x > lo && x < hi)) {
    x = 0.5 * (lo + hi);
  }
  var step_old = hi - lo;
  var step = step_old;
  for (var i = 0; i < CELL_ROOT_MAX_STEPS; i++) {
    let gx = cell_cubic_value(k, x);
    if (gx == 0.0) {
      return x;
    }
    if ((gx < 0.0) == lo_negative) {
      lo = x;
    } else {
      hi = x;
    }
    let slope = cell_cubic_slope(k, x);
    let newton_step = gx / select(1.0, slope, slope != 0.0);
    let newton = x - newton_step;
    step_old = step;
    if (slope == 0.0 || !(newton > lo && newton < hi) || abs(2.0 * gx) > abs(step_old * slope)) {
      step = 0.5 * (hi - lo);
      x = lo + step;
    } else {
      step = newton_step;
      x = newton;
    }
    if (abs(step) <= CELL_ROOT_TOLERANCE) {
      break;
    }
  }
  return clamp(x, lo, hi);
}

// The root of g on the piece [lo, hi] (g monotonic there), or CELL_ROOT_NONE.
fn cell_cubic_piece_root(k: CellCubic, lo: f32, hi: f32) -> f32 {
  let glo = cell_cubic_value(k, lo);
  if (glo == 0.0) {
    return lo;
  }
  let ghi = cell_cubic_value(k, hi);
  if (ghi == 0.0) {
    return hi;
  }
  if ((glo < 0.0) == (ghi < 0.0)) {
    return CELL_ROOT_NONE;
  }
  return cell_cubic_refine(k, lo, hi, glo, ghi);
}

// The smallest s in [0, 1] with g(s) == 0, or CELL_ROOT_NONE.
fn cell_cubic_first_root(k: CellCubic) -> f32 {
  // Split points: the roots of g'(s) = qa s^2 + qb s + qc, by the stable
  // formula (no cancellation; qa == 0 leaves the linear root qc / q = -qc / qb).
  let qa = 3.0 * k.a;
  let qb = 2.0 * k.b;
  let qc = k.c;
  var r1 = 1.0;
  var r2 = 1.0;
  let disc = qb * qb - 4.0 * qa * qc;
  if (disc >= 0.0) {
    let q = -0.5 * (qb + select(-1.0, 1.0, qb >= 0.0) * sqrt(disc));
    if (q != 0.0) {
      r1 = clamp(qc / q, 0.0, 1.0);
      if (qa != 0.0) {
        r2 = clamp(q / qa, 0.0, 1.0);
      }
    }
  }
  // Pieces [0, s1], [s1, s2], [s2, 1] (empty ones cost an evaluation, no more).
  var ends = array<f32, 4>(0.0, min(r1, r2), max(r1, r2), 1.0);
  for (var i = 0; i < 3; i++) {
    let r = cell_cubic_piece_root(k, ends[i], ends[i + 1]);
    if (r >= 0.0) {
      return r;
    }
  }
  return CELL_ROOT_NONE;
}

// The smallest t in [t0, t1] where the trilinear interpolant of the cell
// (corners v, x fastest) along origin + t dir equals iso, or CELL_ROOT_NONE.
fn cell_first_crossing(v: array<f32, 8>, iso: f32, origin: vec3f, dir: vec3f, t0: f32, t1: f32) -> f32 {
  if (!(t1 >= t0)) {
    return CELL_ROOT_NONE;
  }
  // Shift by iso and scale by the largest magnitude: values in [-1, 1].
  var w: array<f32, 8>;
  var m = 0.0;
  for (var i = 0; i < 8; i++) {
    w[i] = v[i] - iso;
    m = max(m, abs(w[i]));
  }
  if (m == 0.0) {
    return t0; // the whole cell is on the surface
  }
  for (var i = 0; i < 8; i++) {
    w[i] = w[i] / m;
  }
  let chord = t1 - t0;
  let k = cell_cubic(w, origin + t0 * dir, chord * dir);
  let s = cell_cubic_first_root(k);
  if (s < 0.0) {
    return CELL_ROOT_NONE;
  }
  return min(t0 + s * chord, t1);
}
