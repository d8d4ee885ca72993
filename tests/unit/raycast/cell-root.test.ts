// The first crossing of a ray with a cell's trilinear interpolant
// (shaders/raycast/cell_root.wgsl on Dawn, and its TS twin src/raycast/cell-root.ts)
// against NumPy: the reference samples the trilinear formula (the sum of corner
// values times products of weights, in float64) at 4 points of the ray's
// interval, fits the cubic exactly (a 4x4 Vandermonde solve), takes its real
// roots (numpy.polynomial.polynomial.polyroots, polished by Newton in float64)
// in [t0, t1]. None of our coefficient code is involved.
//
// Cases (f32 inputs, the same for all three): random cells and rays (entry at
// the origin or far behind it, any direction length), saddle cells (several
// crossings), cubics built with three crossings along a ray (the FIRST must be
// found), double roots (tangent surfaces), rays along axes, edges and face
// diagonals (d with zero components), rays touching the cell only at a corner
// or an edge (t0 == t1), iso equal to a corner value, no crossing, d == 0,
// flat cells, values scaled to 1e-30 and 1e30 or offset by 1e6, and cells
// sampled from the distance to a point (a sphere).
//
// Each case is judged from the reference alone ("near-touch": a critical
// point or an end of [t0, t1] where |f - iso| <= 1e-5 of the largest
// |corner - iso|):
//   exact       f == iso exactly at t0 (a corner of value iso, a flat cell):
//               both return exactly t0;
//   clean       the first root crosses with |df/ds| >= 1e-2 of that scale
//               (s: length along the ray, in cells), with no near-touch before
//               it or within 1e-4 of it: |t - t_ref| |dir| < 1e-4;
//   none        no root and no near-touch: both say none;
//   tangential  otherwise (double roots, near-touches, a root at the interval's
//               end where f32 cannot tell the sign, a crossing at a grazing
//               angle): either answer, but a hit must lie on the surface
//               (|f - iso| <= 1e-4 of the scale) and not after the first clean
//               crossing, and a clean crossing further on must not be missed.
// The sphere cases also put every hit within the trilinear sampling error of
// the analytic sphere (1 / (4 (R - sqrt 3)) for the distance |x - c|).
import { mulberry32 } from '../../../src/util/random.ts';
import { mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { describe, expect, test } from 'vitest';
import cellRootTestWgsl from '../../../shaders/raycast/cell_root_test.wgsl?raw';
import { readF32 } from '../../../src/gpu/buffers.ts';
import { createComputePipeline } from '../../../src/gpu/pipeline-cache.ts';
import { CELL_ROOT_NONE, type CellVec3, cellFirstCrossing, cellGradient } from '../../../src/raycast/cell-root.ts';
import { cellRootSnippet } from '../../../src/raycast/cell-root-wgsl.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { runPython } from '../../helpers/python.ts';

const STRIDE = 17; // 8 corners, iso, origin (3), dir (3), t0, t1
const CLEAN_SLOPE = 1e-2;
const TOUCH = 1e-5;
const TOLERANCE = 1e-4;

interface Sphere {
  centre: CellVec3;
  radius: number;
}

/** The parameter interval of origin + t dir inside the unit cube, or undefined. */
function slab(o: CellVec3, d: CellVec3): [number, number] | undefined {
  let ta = Number.NEGATIVE_INFINITY;
  let tb = Number.POSITIVE_INFINITY;
  for (let a = 0; a < 3; a++) {
    if (d[a] === 0) {
      if (o[a] < 0 || o[a] > 1) return undefined;
      continue;
    }
    const u = -o[a] / d[a];
    const w = (1 - o[a]) / d[a];
    ta = Math.max(ta, Math.min(u, w));
    tb = Math.min(tb, Math.max(u, w));
  }
  return ta <= tb ? [ta, tb] : undefined;
}

/** Corner values of the trilinear k0 + kx x + ... + kxyz xyz (x fastest). */
function cornersOf(k0: number, k1: CellVec3, k2: CellVec3, kxyz: number): number[] {
  const [kx, ky, kz] = k1;
  const [kxy, kxz, kyz] = k2;
  return [
    k0,
    k0 + kx,
    k0 + ky,
    k0 + kx + ky + kxy,
    k0 + kz,
    k0 + kx + kz + kxz,
    k0 + ky + kz + kyz,
    k0 + kx + ky + kz + kxy + kxz + kyz + kxyz,
  ];
}

function buildCases(): { data: Float32Array<ArrayBuffer>; kinds: string[]; spheres: Map<number, Sphere> } {
  const r = mulberry32(46);
  const rows: number[][] = [];
  const kinds: string[] = [];
  const spheres = new Map<number, Sphere>();
  const add = (kind: string, v: number[], iso: number, o: CellVec3, d: CellVec3, t0: number, t1: number) => {
    rows.push([...v, iso, ...o, ...d, t0, t1]);
    kinds.push(kind);
  };
  const unit = (): CellVec3 => {
    for (;;) {
      const d: CellVec3 = [2 * r() - 1, 2 * r() - 1, 2 * r() - 1];
      const n = Math.hypot(...d);
      if (n > 0.1 && n <= 1) return [d[0] / n, d[1] / n, d[2] / n];
    }
  };
  // A ray through point p of the cube along d: entry as origin (t0 = 0), or
  // an origin up to 3 cells behind the entry.
  const ray = (kind: string, v: number[], iso: number, p: CellVec3, d: CellVec3) => {
    const span = slab(p, d);
    if (!span) return;
    const [ta, tb] = span;
    const back = r() < 0.5 ? 0 : 3 * r();
    const o: CellVec3 = [p[0] + (ta - back) * d[0], p[1] + (ta - back) * d[1], p[2] + (ta - back) * d[2]];
    add(kind, v, iso, o, d, back, back + (tb - ta));
  };
  const point = (): CellVec3 => [r(), r(), r()];
  const scaled = (d: CellVec3): CellVec3 => {
    const s = r() < 0.7 ? 1 : 10 ** (4 * r() - 2);
    return [d[0] * s, d[1] * s, d[2] * s];
  };

  // Random cells, random rays.
  for (let i = 0; i < 3000; i++) {
    const v = Array.from({ length: 8 }, () => 2 * r() - 1);
    ray('random', v, 1.2 * r() - 0.6, point(), scaled(unit()));
  }
  // Saddles (corners of alternating sign): two crossings along many rays.
  for (let i = 0; i < 400; i++) {
    const v = Array.from({ length: 8 }, (_, c) => ((c ^ (c >> 1) ^ (c >> 2)) & 1 ? 1 : -1) * (0.5 + r()));
    ray('saddle', v, 0.3 * r() - 0.15, point(), unit());
  }
  // Three crossings (and double roots) along a diagonal: g(s) = A (s - r1)(s - r2)(s - r3).
  const split = (total: number): CellVec3 => {
    const w = [r(), r(), r()];
    const sum = w[0] + w[1] + w[2];
    return [(total * w[0]) / sum, (total * w[1]) / sum, (total * w[2]) / sum];
  };
  for (let i = 0; i < 400; i++) {
    const double = i % 4 === 3;
    const r1 = 0.05 + 0.25 * r();
    const r2 = double ? r1 : r1 + 0.1 + 0.25 * r();
    const r3 = double && r() < 0.5 ? 1.2 + r() : Math.min(r2 + 0.1 + 0.4 * r(), 0.97);
    const A = (r() < 0.5 ? 1 : -1) * (1 + 4 * r());
    const iso = 4 * r() - 2;
    const v = cornersOf(-A * r1 * r2 * r3 + iso, split(A * (r1 * r2 + r1 * r3 + r2 * r3)), split(-A * (r1 + r2 + r3)), A);
    // Along the diagonal from any of the 4 corners (flip axes), sometimes tilted.
    const flip = Math.floor(4 * r());
    const vf = v.map((_, c) => v[c ^ flip]);
    const o: CellVec3 = [flip & 1, (flip >> 1) & 1, 0];
    const tilt = r() < 0.5 ? 0 : 0.05;
    const d: CellVec3 = [(flip & 1 ? -1 : 1) * (1 - tilt * r()), (flip & 2 ? -1 : 1) * (1 - tilt * r()), 1 - tilt * r()];
    const span = slab(o, d);
    if (span) add(double ? 'double root' : 'three crossings', vf, iso, o, d, 0, span[1]);
  }
  // Rays along axes and face diagonals (zero components), from points on
  // faces, edges and corners.
  for (let i = 0; i < 600; i++) {
    const v = Array.from({ length: 8 }, () => 2 * r() - 1);
    const d: [number, number, number] = [0, 0, 0];
    const nonzero = 1 + Math.floor(2 * r());
    const first = Math.floor(3 * r());
    for (let j = 0; j < nonzero; j++) d[(first + j) % 3] = r() < 0.5 ? -1 : 1;
    const p: [number, number, number] = [r(), r(), r()];
    const snap = Math.floor(4 * r()); // how many coordinates sit on 0 or 1
    for (let j = 0; j < snap && j < 3; j++) p[(first + 1 + j) % 3] = r() < 0.5 ? 0 : 1;
    ray('axis/edge', v, 1.2 * r() - 0.6, p, d);
  }
  // iso equal to a corner value: rays from that corner, and rays ending there.
  for (let i = 0; i < 300; i++) {
    const v = Array.from({ length: 8 }, () => 2 * r() - 1);
    const c = Math.floor(8 * r());
    const corner: CellVec3 = [c & 1, (c >> 1) & 1, c >> 2];
    const p = point();
    const d: CellVec3 = [p[0] - corner[0], p[1] - corner[1], p[2] - corner[2]];
    if (i % 2 === 0) add('iso at corner', v, v[c], corner, d, 0, slab(corner, d)?.[1] ?? 0);
    else {
      const back: CellVec3 = [-d[0], -d[1], -d[2]];
      const span = slab(p, back);
      if (span) add('iso at corner', v, v[c], p, back, 0, span[1]);
    }
  }
  // Rays touching the cell only at a corner or along an outer edge (t0 == t1
  // at the corner), with iso at that corner's value or not; t0 == t1 inside.
  for (let i = 0; i < 200; i++) {
    const v = Array.from({ length: 8 }, () => 2 * r() - 1);
    const c = Math.floor(8 * r());
    const corner: CellVec3 = [c & 1, (c >> 1) & 1, c >> 2];
    // Out of the cube along x, into -y: touches only the corner.
    const d: CellVec3 = [corner[0] ? 1 : -1, corner[1] ? -1 : 1, 0];
    const o: CellVec3 = [corner[0] - 0.5 * d[0], corner[1] - 0.5 * d[1], corner[2]];
    add('touch corner', v, i % 2 ? v[c] : 1.2 * r() - 0.6, o, d, 0.5, 0.5);
    const p = point();
    add('t0 == t1', v, 1.2 * r() - 0.6, p, unit(), 0, 0);
  }
  // No crossing; flat cells; d == 0.
  for (let i = 0; i < 100; i++) {
    const v = Array.from({ length: 8 }, () => 0.01 + r());
    ray('no crossing', v, i % 2 ? 0 : -r(), point(), unit());
    const iso = 2 * r() - 1;
    ray('flat (all iso)', new Array(8).fill(iso), iso, point(), unit());
    // d == 0: f(origin) is iso only when the origin is a corner of value iso.
    const c = Math.floor(8 * r());
    add('d == 0', v, i % 2 ? 0.5 : v[c], i % 2 ? point() : [c & 1, (c >> 1) & 1, c >> 2], [0, 0, 0], 0, 1);
  }
  // Tiny and huge values, large offsets.
  for (const scale of [1e-30, 1e-20, 1e20, 1e30]) {
    for (let i = 0; i < 100; i++) {
      const v = Array.from({ length: 8 }, () => scale * (2 * r() - 1));
      ray(`scale ${scale}`, v, scale * (1.2 * r() - 0.6), point(), scaled(unit()));
    }
  }
  for (let i = 0; i < 100; i++) {
    const v = Array.from({ length: 8 }, () => 1e6 + 64 * (2 * r() - 1));
    ray('offset 1e6', v, 1e6 + 64 * (1.2 * r() - 0.6), point(), unit());
  }
  // Cells sampled from |x - centre| (cell-local centre), around a point on the
  // sphere of radius R inside the cell, with a ray through that point not
  // grazing the sphere (|cos| >= 0.3 with the normal).
  for (let i = 0; i < 400; i++) {
    const radius = 6 + 20 * r();
    const n = unit();
    const onSurface: CellVec3 = [0.2 + 0.6 * r(), 0.2 + 0.6 * r(), 0.2 + 0.6 * r()];
    const centre: CellVec3 = [onSurface[0] - radius * n[0], onSurface[1] - radius * n[1], onSurface[2] - radius * n[2]];
    const v = Array.from({ length: 8 }, (_, c) => Math.hypot((c & 1) - centre[0], ((c >> 1) & 1) - centre[1], (c >> 2) - centre[2]));
    let d = unit();
    while (Math.abs(d[0] * n[0] + d[1] * n[1] + d[2] * n[2]) < 0.3) d = unit();
    // Inward, so the first crossing is the sphere's (entering it).
    if (d[0] * n[0] + d[1] * n[1] + d[2] * n[2] > 0) d = [-d[0], -d[1], -d[2]];
    const before = rows.length;
    ray('sphere', v, radius, onSurface, d);
    if (rows.length > before) spheres.set(before, { centre, radius });
  }
  return { data: Float32Array.from(rows.flat()), kinds, spheres };
}

interface Reference {
  /** Real roots in [t0, t1], ascending. */
  roots: number[];
  /** |df/ds| / scale at each root (s: length along the ray). */
  slopes: number[];
  /** Critical points and interval ends where f comes within 1e-5 of the scale of iso. */
  touches: number[];
  /** The cubic in u = (t - t0) / (t1 - t0), low to high, divided by the scale. */
  poly: number[];
  /** max |corner - iso|. */
  scale: number;
  /** The gradient at the origin, by central differences (exact for a trilinear). */
  gradient: number[];
  /** f(t0) == iso exactly (or every corner equals iso): a hit at exactly t0. */
  zeroAtT0: boolean;
}

const REFERENCE_PY = `
import json, sys
import numpy as np
from numpy.polynomial import polynomial as P

cases = np.fromfile(sys.argv[1], dtype='<f8').reshape(-1, 17)
v, iso, o, d, t0, t1 = cases[:, :8], cases[:, 8], cases[:, 9:12], cases[:, 12:15], cases[:, 15], cases[:, 16]

def trilinear(p):
    # p: (N, K, 3) -> (N, K), sum over corners of value * weights
    out = np.zeros(p.shape[:2])
    for c in range(8):
        w = np.ones(p.shape[:2])
        for a in range(3):
            w = w * (p[..., a] if (c >> a) & 1 else 1.0 - p[..., a])
        out += v[:, c:c + 1] * w
    return out

nodes = np.array([0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0])
chord = t1 - t0
ts = t0[:, None] + nodes[None, :] * chord[:, None]
vals = trilinear(o[:, None, :] + ts[..., None] * d[:, None, :]) - iso[:, None]
coef = np.linalg.solve(np.vander(nodes, 4, increasing=True)[None], vals[..., None])[..., 0]
scale = np.max(np.abs(v - iso[:, None]), axis=1)
h = 0.5
grad = np.stack([(trilinear((o + h * e)[:, None, :]) - trilinear((o - h * e)[:, None, :]))[:, 0] / (2 * h) for e in np.eye(3)], axis=1)

out = []
for i in range(len(cases)):
    m = scale[i]
    ref = {'roots': [], 'slopes': [], 'touches': [], 'poly': [], 'scale': float(m), 'gradient': grad[i].tolist(),
           'zeroAtT0': bool(m == 0 or vals[i, 0] == 0)}
    out.append(ref)
    if m == 0:
        continue
    if chord[i] == 0:
        if abs(vals[i, 0]) <= ${TOUCH} * m:
            ref['touches'] = [float(t0[i])]
        continue
    c = coef[i] / m
    ref['poly'] = c.tolist()
    big = np.max(np.abs(c))
    if big == 0:
        continue
    dc = P.polyder(c)
    trimmed = c.copy()
    while len(trimmed) > 1 and abs(trimmed[-1]) <= 1e-12 * big:
        trimmed = trimmed[:-1]
    roots = []
    if len(trimmed) > 1:
        for z in P.polyroots(trimmed):
            if abs(z.imag) > 1e-6:
                continue
            u = z.real
            for _ in range(3):
                s = P.polyval(u, dc)
                if s != 0:
                    u -= P.polyval(u, c) / s
            if -1e-9 <= u <= 1 + 1e-9:
                roots.append(min(max(u, 0.0), 1.0))
    roots.sort()
    length = chord[i] * np.linalg.norm(d[i])
    ref['roots'] = [float(t0[i] + u * chord[i]) for u in roots]
    ref['slopes'] = [float(abs(P.polyval(u, dc)) / length) if length > 0 else 0.0 for u in roots]
    # Near-touches: critical points, and the interval's ends, where f comes within TOUCH of iso.
    near = [0.0, 1.0]
    if np.max(np.abs(dc)) > 0:
        dt = dc.copy()
        while len(dt) > 1 and abs(dt[-1]) <= 1e-12 * np.max(np.abs(dc)):
            dt = dt[:-1]
        near += [z.real for z in (P.polyroots(dt) if len(dt) > 1 else []) if abs(z.imag) <= 1e-9 and 0 <= z.real <= 1]
    ref['touches'] = sorted(float(t0[i] + u * chord[i]) for u in near if abs(P.polyval(u, c)) <= ${TOUCH})
print(json.dumps(out))
`;

const { data: cases, kinds, spheres } = buildCases();
const count = kinds.length;
let reference: Reference[] | undefined;

function getReference(): Reference[] {
  if (!reference) {
    const dir = mkdtempSync(join(tmpdir(), 'cell-root-'));
    try {
      const path = join(dir, 'cases.f64');
      writeFileSync(path, new Float64Array(cases));
      reference = JSON.parse(runPython(REFERENCE_PY, [path])) as Reference[];
    } finally {
      rmSync(dir, { recursive: true, force: true });
    }
  }
  return reference;
}

const caseAt = (i: number) => {
  const b = STRIDE * i;
  return {
    v: Array.from(cases.subarray(b, b + 8)),
    iso: cases[b + 8],
    origin: [cases[b + 9], cases[b + 10], cases[b + 11]] as CellVec3,
    dir: [cases[b + 12], cases[b + 13], cases[b + 14]] as CellVec3,
    t0: cases[b + 15],
    t1: cases[b + 16],
  };
};

interface Tally {
  exact: number;
  clean: number;
  none: number;
  tangential: number;
  tangentialHits: number;
  multiple: number;
  maxError: number;
  perKind: Map<string, string>;
}

/** Judges one implementation's answers (t per case) against the reference; returns the figures. */
function judge(label: string, answers: ArrayLike<number>): Tally {
  const refs = getReference();
  const tally: Tally = { exact: 0, clean: 0, none: 0, tangential: 0, tangentialHits: 0, multiple: 0, maxError: 0, perKind: new Map() };
  const failures: string[] = [];
  const kindCounts = new Map<string, number[]>();
  for (let i = 0; i < count; i++) {
    const ref = refs[i];
    const { dir, t0, t1 } = caseAt(i);
    const t = answers[i];
    const dn = Math.hypot(...dir) || 1;
    const why = (msg: string) => failures.push(`${label} case ${i} (${kinds[i]}): ${msg}; ours ${t}, ref ${JSON.stringify(ref)}`);
    if (t !== CELL_ROOT_NONE && !(t >= t0 && t <= t1)) why('outside [t0, t1]');
    const roots = ref.roots;
    // The first root crossing clean, away from near-touches (and interval ends where f is near iso).
    const firstClean = ref.slopes.findIndex(
      (s, j) => s >= CLEAN_SLOPE && !ref.touches.some((x) => Math.abs(x - roots[j]) * dn < TOLERANCE),
    );
    if (roots.length > 1) tally.multiple++;
    const counts = kindCounts.get(kinds[i]) ?? [0, 0, 0];
    kindCounts.set(kinds[i], counts);
    if (ref.zeroAtT0) {
      // Flat cells, f == iso exactly at the entry (a corner of value iso): a hit at exactly t0.
      tally.exact++;
      counts[0]++;
      if (t !== t0) why('expected the exact hit at t0');
    } else if (firstClean === 0 && !ref.touches.some((x) => x < roots[0])) {
      tally.clean++;
      counts[0]++;
      const err = t === CELL_ROOT_NONE ? Number.POSITIVE_INFINITY : Math.abs(t - roots[0]) * dn;
      tally.maxError = Math.max(tally.maxError, err);
      if (!(err < TOLERANCE)) why(`error ${err}`);
    } else if (roots.length === 0 && ref.touches.length === 0) {
      tally.none++;
      counts[1]++;
      if (t !== CELL_ROOT_NONE) why('expected none');
    } else {
      tally.tangential++;
      counts[2]++;
      if (firstClean >= 0 && t === CELL_ROOT_NONE) why('missed a clean crossing after a tangential one');
      if (t !== CELL_ROOT_NONE) {
        tally.tangentialHits++;
        if (firstClean >= 0 && (t - roots[firstClean]) * dn > TOLERANCE) why('a hit after the first clean crossing');
        if (ref.poly.length > 0) {
          const u = (t - t0) / (t1 - t0);
          const residual = Math.abs(ref.poly.reduceRight((acc, c) => acc * u + c, 0));
          if (residual > 10 * TOUCH) why(`a hit off the surface (|f - iso| = ${residual} of the scale)`);
        }
      }
    }
  }
  for (const [k, [c, n, tg]] of kindCounts) tally.perKind.set(k, `${c} exact or clean, ${n} none, ${tg} tangential`);
  expect(failures.slice(0, 10), `${failures.length} failures`).toEqual([]);
  return tally;
}

/** Sphere cases: the hit lies within the trilinear sampling error of the analytic sphere. */
function judgeSpheres(label: string, answers: ArrayLike<number>): number {
  let worst = 0;
  for (const [i, { centre, radius }] of spheres) {
    const { origin, dir } = caseAt(i);
    const t = answers[i];
    expect(t, `${label} sphere case ${i}`).not.toBe(CELL_ROOT_NONE);
    const p = [0, 1, 2].map((a) => origin[a] + t * dir[a] - centre[a]);
    const off = Math.abs(Math.hypot(...p) - radius);
    // |f - I f| <= (h^2 / 8) trace|H| = 1 / (4 r) for f = |x - c|, r >= R - sqrt(3).
    const bound = 1 / (4 * (radius - Math.sqrt(3)));
    worst = Math.max(worst, off / bound);
    expect(off, `${label} sphere case ${i}: ${off} from the sphere`).toBeLessThanOrEqual(bound + 1e-4);
  }
  return worst;
}

function report(label: string, tally: Tally, sphereWorst: number, ms: number): void {
  console.info(
    `${label}: ${count} cases: ${tally.exact} exact at t0, ${tally.clean} clean (max |dt| |d| = ${tally.maxError.toExponential(2)}), ${tally.none} none, ` +
      `${tally.tangential} tangential (${tally.tangentialHits} hits), ${tally.multiple} with several roots; ` +
      `sphere hits at most ${sphereWorst.toFixed(2)} of the sampling bound; ${ms.toFixed(0)} ms\n  ` +
      [...tally.perKind].map(([k, s]) => `${k}: ${s}`).join('\n  '),
  );
}

describe('first crossing of a ray with the trilinear interpolant', () => {
  test('the cases cover what they should (the reference sees several roots, tangents, none)', () => {
    const refs = getReference();
    const three = refs.filter(
      (ref, i) => kinds[i] === 'three crossings' && ref.roots.length === 3 && ref.slopes.every((s) => s >= CLEAN_SLOPE),
    );
    expect(three.length).toBeGreaterThan(100);
    expect(refs.filter((ref) => ref.roots.length >= 2).length).toBeGreaterThan(300);
    expect(refs.filter((ref) => ref.roots.length === 0).length).toBeGreaterThan(500);
    expect(refs.filter((ref) => ref.touches.length > 0 || ref.slopes.some((s) => s > 0 && s < CLEAN_SLOPE)).length).toBeGreaterThan(20);
    expect(spheres.size).toBeGreaterThan(300);
  });

  test('TS mirror against NumPy', () => {
    const started = performance.now();
    const answers = new Float64Array(count);
    for (let i = 0; i < count; i++) {
      const { v, iso, origin, dir, t0, t1 } = caseAt(i);
      answers[i] = cellFirstCrossing(v, iso, origin, dir, t0, t1);
    }
    const ms = performance.now() - started;
    const tally = judge('ts', answers);
    report('ts', tally, judgeSpheres('ts', answers), ms);
    // Gradients: central differences of the trilinear are exact.
    const refs = getReference();
    for (let i = 0; i < count; i++) {
      const { v, origin } = caseAt(i);
      const g = cellGradient(v, origin);
      const spread = Math.max(...v.map((x) => Math.abs(x - v[0]))) + 1e-300;
      const err = Math.max(...g.map((x, a) => Math.abs(x - refs[i].gradient[a]))) / spread;
      expect(err, `ts gradient case ${i}`).toBeLessThan(1e-9 * (1 + Math.hypot(...origin)) * (Math.abs(v[0]) / spread + 1));
    }
  });

  gpuTest('WGSL on Dawn against NumPy', async ({ gpu }) => {
    const { device } = gpu;
    const started = performance.now();
    const input = device.createBuffer({
      label: 'test.cellRoot.cases',
      size: cases.byteLength,
      usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST,
    });
    device.queue.writeBuffer(input, 0, cases);
    const output = device.createBuffer({
      label: 'test.cellRoot.results',
      size: 16 * count,
      usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC,
    });
    const pipeline = await createComputePipeline(
      device,
      'test.cellRoot',
      [cellRootSnippet, { name: 'shaders/raycast/cell_root_test.wgsl', code: cellRootTestWgsl }],
      'main',
    );
    const bind = device.createBindGroup({
      layout: pipeline.getBindGroupLayout(0),
      entries: [input, output].map((buffer, binding) => ({ binding, resource: { buffer } })),
    });
    const encoder = device.createCommandEncoder();
    const pass = encoder.beginComputePass();
    pass.setPipeline(pipeline);
    pass.setBindGroup(0, bind);
    pass.dispatchWorkgroups(Math.ceil(count / 64));
    pass.end();
    device.queue.submit([encoder.finish()]);
    const results = await readF32(device, output);
    const ms = performance.now() - started;
    const answers = Float64Array.from({ length: count }, (_, i) => results[4 * i]);
    const tally = judge('gpu', answers);
    report('gpu', tally, judgeSpheres('gpu', answers), ms);
    const refs = getReference();
    for (let i = 0; i < count; i++) {
      const { v, origin } = caseAt(i);
      const spread = Math.max(...v.map((x) => Math.abs(x - v[0])));
      const ulps = (4 * Math.max(...v.map(Math.abs))) / 2 ** 23;
      const err = Math.max(...[0, 1, 2].map((a) => Math.abs(results[4 * i + 1 + a] - refs[i].gradient[a])));
      expect(err, `gpu gradient case ${i}`).toBeLessThanOrEqual((1e-5 * spread + ulps) * (1 + Math.hypot(...origin)));
    }
    input.destroy();
    output.destroy();
  });
});
