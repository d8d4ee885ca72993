// Metrics of triangle soups (xyz per vertex, 3 vertices per triangle) and a
// tolerant comparison of two soups as sets of triangles. Used to check every
// marching cubes against the serial one and against VTK's figures (mc.json).

export interface BBox {
  min: [number, number, number];
  max: [number, number, number];
}

export interface MeshMetrics {
  triangles: number;
  /** Sum of triangle areas in float64 from the float32 positions. */
  area: number;
  /** Null for an empty soup. */
  bbox: BBox | null;
  /** Triangles of zero area (float64), as mc.json counts them. */
  degenerate: number;
}

function checkSoup(positions: ArrayLike<number>, vertexCount: number): void {
  if (vertexCount % 3 !== 0 || vertexCount * 3 > positions.length) {
    throw new Error(`triangle soup: ${vertexCount} vertices in ${positions.length} floats`);
  }
}

/** Metrics of the first `vertexCount` vertices (default: all) of a soup. */
export function meshMetrics(positions: Float32Array, vertexCount = Math.floor(positions.length / 3)): MeshMetrics {
  checkSoup(positions, vertexCount);
  const triangles = vertexCount / 3;
  let area = 0;
  let degenerate = 0;
  let x0 = Infinity,
    y0 = Infinity,
    z0 = Infinity;
  let x1 = -Infinity,
    y1 = -Infinity,
    z1 = -Infinity;
  for (let v = 0; v < vertexCount * 3; v += 3) {
    const x = positions[v],
      y = positions[v + 1],
      z = positions[v + 2];
    if (x < x0) x0 = x;
    if (x > x1) x1 = x;
    if (y < y0) y0 = y;
    if (y > y1) y1 = y;
    if (z < z0) z0 = z;
    if (z > z1) z1 = z;
  }
  for (let p = 0; p < vertexCount * 3; p += 9) {
    const ax = positions[p + 3] - positions[p],
      ay = positions[p + 4] - positions[p + 1],
      az = positions[p + 5] - positions[p + 2];
    const bx = positions[p + 6] - positions[p],
      by = positions[p + 7] - positions[p + 1],
      bz = positions[p + 8] - positions[p + 2];
    const cx = ay * bz - az * by,
      cy = az * bx - ax * bz,
      cz = ax * by - ay * bx;
    const a = 0.5 * Math.sqrt(cx * cx + cy * cy + cz * cz);
    if (a === 0) degenerate++;
    area += a;
  }
  const bbox: BBox | null = vertexCount === 0 ? null : { min: [x0, y0, z0], max: [x1, y1, z1] };
  return { triangles, area, bbox, degenerate };
}

export interface SoupComparison {
  /** Every triangle of each soup matched one of the other (bijection), within tol. */
  equal: boolean;
  trianglesA: number;
  trianglesB: number;
  matched: number;
  unmatchedA: number;
  unmatchedB: number;
  /** Largest coordinate difference among matched triangles. */
  maxDifference: number;
  /** Up to 5 unmatched triangles of each soup (9 numbers each), to help debugging. */
  examplesA: number[][];
  examplesB: number[][];
}

export interface CompareOptions {
  /** Largest allowed difference per coordinate (voxel units). Default 1e-4. */
  tolerance?: number;
  /** Number of vertices of each soup to use (default: all). */
  vertexCountA?: number;
  vertexCountB?: number;
}

/**
 * Compares two soups as sets of triangles: triangle order and each triangle's
 * starting vertex may differ, winding may not (a rotation (p0,p1,p2) -> (p1,p2,p0)
 * keeps the normal; a reflection flips it and does not match).
 *
 * Each triangle is rotated to start at its lexicographically smallest vertex, both
 * lists are sorted and merged with the tolerance. Near-ties can order differently
 * on the two sides, so what the merge leaves over is matched again by a spatial
 * hash of the centroids that tries all three rotations.
 */
export function compareTriangleSoups(a: Float32Array, b: Float32Array, options: CompareOptions = {}): SoupComparison {
  const tol = options.tolerance ?? 1e-4;
  const nA = options.vertexCountA ?? Math.floor(a.length / 3);
  const nB = options.vertexCountB ?? Math.floor(b.length / 3);
  checkSoup(a, nA);
  checkSoup(b, nB);
  const ca = canonical(a, nA / 3);
  const cb = canonical(b, nB / 3);
  const oa = sortedOrder(ca);
  const ob = sortedOrder(cb);

  let maxDifference = 0;
  let matched = 0;
  const leftA: number[] = [];
  const leftB: number[] = [];
  let i = 0;
  let j = 0;
  while (i < oa.length && j < ob.length) {
    const d = maxDiff(ca, oa[i], cb, ob[j], 0);
    if (d <= tol) {
      if (d > maxDifference) maxDifference = d;
      matched++;
      i++;
      j++;
    } else if (compareTri(ca, oa[i], cb, ob[j]) < 0) {
      leftA.push(oa[i++]);
    } else {
      leftB.push(ob[j++]);
    }
  }
  while (i < oa.length) leftA.push(oa[i++]);
  while (j < ob.length) leftB.push(ob[j++]);

  // Second chance for the leftovers: centroid grid with cells larger than tol,
  // searching the 27 neighbouring cells, any rotation.
  const cell = Math.max(4 * tol, 1e-6);
  const key = (x: number, y: number, z: number) => `${x},${y},${z}`;
  const centroidCell = (s: Float32Array, t: number, axis: number) =>
    Math.floor((s[9 * t + axis] + s[9 * t + 3 + axis] + s[9 * t + 6 + axis]) / 3 / cell);
  const grid = new Map<string, number[]>();
  for (const t of leftB) {
    const k = key(centroidCell(cb, t, 0), centroidCell(cb, t, 1), centroidCell(cb, t, 2));
    const list = grid.get(k);
    if (list) list.push(t);
    else grid.set(k, [t]);
  }
  const usedB = new Set<number>();
  const stillA: number[] = [];
  for (const t of leftA) {
    const gx = centroidCell(ca, t, 0),
      gy = centroidCell(ca, t, 1),
      gz = centroidCell(ca, t, 2);
    let found = -1;
    let foundDiff = Infinity;
    search: for (let dz = -1; dz <= 1; dz++) {
      for (let dy = -1; dy <= 1; dy++) {
        for (let dx = -1; dx <= 1; dx++) {
          for (const u of grid.get(key(gx + dx, gy + dy, gz + dz)) ?? []) {
            if (usedB.has(u)) continue;
            for (let r = 0; r < 3; r++) {
              const d = maxDiff(ca, t, cb, u, r);
              if (d <= tol) {
                found = u;
                foundDiff = d;
                break search;
              }
            }
          }
        }
      }
    }
    if (found < 0) {
      stillA.push(t);
    } else {
      usedB.add(found);
      matched++;
      if (foundDiff > maxDifference) maxDifference = foundDiff;
    }
  }
  const stillB = leftB.filter((t) => !usedB.has(t));
  const example = (s: Float32Array, t: number) => Array.from(s.subarray(9 * t, 9 * t + 9));
  return {
    equal: stillA.length === 0 && stillB.length === 0,
    trianglesA: nA / 3,
    trianglesB: nB / 3,
    matched,
    unmatchedA: stillA.length,
    unmatchedB: stillB.length,
    maxDifference,
    examplesA: stillA.slice(0, 5).map((t) => example(ca, t)),
    examplesB: stillB.slice(0, 5).map((t) => example(cb, t)),
  };
}

function lessVertex(s: Float32Array, p: number, q: number): boolean {
  if (s[p] !== s[q]) return s[p] < s[q];
  if (s[p + 1] !== s[q + 1]) return s[p + 1] < s[q + 1];
  return s[p + 2] < s[q + 2];
}

/** Copy of the soup with each triangle rotated to start at its smallest vertex. */
function canonical(src: Float32Array, triangles: number): Float32Array {
  const out = new Float32Array(triangles * 9);
  for (let t = 0; t < triangles; t++) {
    const p = 9 * t;
    let first = 0;
    if (lessVertex(src, p + 3, p)) first = 1;
    if (lessVertex(src, p + 6, p + 3 * first)) first = 2;
    for (let v = 0; v < 3; v++) {
      const from = p + 3 * ((first + v) % 3);
      out[p + 3 * v] = src[from];
      out[p + 3 * v + 1] = src[from + 1];
      out[p + 3 * v + 2] = src[from + 2];
    }
  }
  return out;
}

function compareTri(s: Float32Array, t: number, u: Float32Array, w: number): number {
  for (let m = 0; m < 9; m++) {
    const d = s[9 * t + m] - u[9 * w + m];
    if (d !== 0) return d;
  }
  return 0;
}

function sortedOrder(s: Float32Array): Uint32Array {
  const order = Uint32Array.from({ length: s.length / 9 }, (_, t) => t);
  // Typed-array sort with a comparator: no boxing of the index array.
  return order.sort((t, w) => compareTri(s, t, s, w));
}

/** Largest coordinate difference between triangle t of s and triangle w of u rotated by r. */
function maxDiff(s: Float32Array, t: number, u: Float32Array, w: number, r: number): number {
  let m = 0;
  for (let v = 0; v < 3; v++) {
    const p = 9 * t + 3 * v;
    const q = 9 * w + 3 * ((v + r) % 3);
    for (let c = 0; c < 3; c++) {
      const d = Math.abs(s[p + c] - u[q + c]);
      if (d !== d) return Infinity; // NaN never matches
      if (d > m) m = d;
    }
  }
  return m;
}
