// The one marching-cubes case table of the project (serial TS, C++/Wasm, GPU naive
// and block MC all read it), so every implementation emits the same triangles.
// The triangles are VTK's classic vtkMarchingCubes table (derived by running VTK,
// tools/mc/derive-case-table.py), renumbered to the conventions below. See README.md.
//
// Corners: corner c of cell (i, j, k) is grid point (i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2)).
// Case index: bit c set when corner c is inside, value >= iso.
// Edges: edge e lies along axis a = e >> 2 (0 = x, 1 = y, 2 = z); r = e & 3 places it in
// the two other axes (u, v) = (y, z) | (x, z) | (x, y): u offset = r & 1, v offset = r >> 1.
// It runs from its lower corner (offset 0 along a) to its upper corner (offset 1).
//
//   edge: 0  1  2  3 | 4  5  6  7 | 8  9 10 11
//   axis: x  x  x  x | y  y  y  y | z  z  z  z
//   lo:   0  2  4  6 | 0  1  4  5 | 0  1  2  3
//   hi:   1  3  5  7 | 2  3  6  7 | 4  5  6  7
//
// Winding: the right-hand normal (p1 - p0) x (p2 - p0) points toward decreasing values.
import { CASE_TRIANGLE_EDGES } from './case-table-data.ts';

export { CASE_TRIANGLE_EDGES };

/** Most vertices a case emits (5 triangles). */
export const MAX_CASE_VERTICES = 15;
/** Row stride of CASE_EDGE_TABLE. */
export const CASE_TABLE_STRIDE = 16;

/** Corner offsets (dx, dy, dz) for corners 0..7, flattened. */
export const CORNER_OFFSETS: Uint8Array = (() => {
  const a = new Uint8Array(24);
  for (let c = 0; c < 8; c++) {
    a[3 * c] = c & 1;
    a[3 * c + 1] = (c >> 1) & 1;
    a[3 * c + 2] = c >> 2;
  }
  return a;
})();

/** Edge axis (0 = x, 1 = y, 2 = z) for edges 0..11. */
export const EDGE_AXIS: Uint8Array = Uint8Array.from({ length: 12 }, (_, e) => e >> 2);

/** Edge e's lower corner at [2e], upper corner at [2e + 1]. */
export const EDGE_CORNERS: Uint8Array = (() => {
  const a = new Uint8Array(24);
  for (let e = 0; e < 12; e++) {
    const axis = e >> 2;
    const r = e & 3;
    const u = axis === 0 ? 1 : 0;
    const v = axis === 2 ? 1 : 2;
    const lo = ((r & 1) << u) | ((r >> 1) << v);
    a[2 * e] = lo;
    a[2 * e + 1] = lo | (1 << axis);
  }
  return a;
})();

/** Vertices emitted by each case (3 per triangle, 0..15). */
export const CASE_VERTEX_COUNT: Uint8Array = Uint8Array.from(CASE_TRIANGLE_EDGES, (t) => t.length);

/** Per case, CASE_TABLE_STRIDE edge indices: the triangles' edges, then -1. */
export const CASE_EDGE_TABLE: Int8Array = (() => {
  const a = new Int8Array(256 * CASE_TABLE_STRIDE).fill(-1);
  CASE_TRIANGLE_EDGES.forEach((t, c) => a.set(t, c * CASE_TABLE_STRIDE));
  return a;
})();

/** Per case, bit e set when edge e has one corner inside and one outside. */
export const CASE_EDGE_MASK: Uint16Array = (() => {
  const a = new Uint16Array(256);
  for (let c = 0; c < 256; c++) {
    let m = 0;
    for (let e = 0; e < 12; e++) if (((c >> EDGE_CORNERS[2 * e]) ^ (c >> EDGE_CORNERS[2 * e + 1])) & 1) m |= 1 << e;
    a[c] = m;
  }
  return a;
})();

/**
 * The table packed for a GPU kernel: 2 u32 per case (2 KiB in all, small enough
 * for a uniform buffer as array<vec4<u32>, 128>). Case c uses words 2c and 2c+1,
 * read as 16 nibbles n[0..15] (n[j] = (word[2c + (j >> 3)] >> (4 * (j & 7))) & 15):
 * n[0..14] are the edge indices of the triangles (vertex j of the case), and n[15]
 * is the triangle count (0..5); unused nibbles are 15.
 */
export function packCaseTable(): Uint32Array {
  const out = new Uint32Array(512);
  for (let c = 0; c < 256; c++) {
    const nib = new Array<number>(16).fill(15);
    CASE_TRIANGLE_EDGES[c].forEach((e, j) => (nib[j] = e));
    nib[15] = CASE_TRIANGLE_EDGES[c].length / 3;
    for (let w = 0; w < 2; w++) {
      let word = 0;
      for (let j = 0; j < 8; j++) word |= nib[8 * w + j] << (4 * j);
      out[2 * c + w] = word >>> 0;
    }
  }
  return out;
}

/** Case index of the 8 corner values (indexed by corner number), value >= iso inside. */
export function caseIndex(corners: ArrayLike<number>, iso: number): number {
  const t = Math.fround(iso);
  let c = 0;
  for (let i = 0; i < 8; i++) if (corners[i] >= t) c |= 1 << i;
  return c;
}
