// Serial marching cubes in TypeScript: the CPU reference for the GPU kernels and
// the "JavaScript" entry of the paper's serial comparison (section 3.3.3). The C++
// twin in benchmarks/serial-mc/serial_mc.cpp follows the same steps in the same order,
// so both produce bit-identical triangle soups.
import { CASE_EDGE_TABLE, CASE_TABLE_STRIDE, CASE_VERTEX_COUNT, EDGE_CORNERS } from './case-table.ts';

export type Dims3 = readonly [number, number, number];

export interface MarchingCubesResult {
  /** Triangle soup: xyz per vertex, 3 vertices per triangle, voxel index space. */
  positions: Float32Array;
  triangleCount: number;
}

const fround = Math.fround;

// Per-edge lower/upper corner and axis, flattened for the inner loop.
const EDGE_LO = Uint8Array.from({ length: 12 }, (_, e) => EDGE_CORNERS[2 * e]);
const EDGE_HI = Uint8Array.from({ length: 12 }, (_, e) => EDGE_CORNERS[2 * e + 1]);

/** Checks dims against the array length; returns the number of cells. */
export function cellCount(values: ArrayLike<number>, dims: Dims3): number {
  const [nx, ny, nz] = dims;
  for (const n of dims) if (!Number.isInteger(n) || n < 1) throw new Error(`bad volume dims ${dims.join('x')}`);
  if (values.length !== nx * ny * nz) throw new Error(`volume has ${values.length} values, dims ${dims.join('x')} need ${nx * ny * nz}`);
  return nx < 2 || ny < 2 || nz < 2 ? 0 : (nx - 1) * (ny - 1) * (nz - 1);
}

/**
 * Isosurface of a scalar volume (x fastest: value (i, j, k) at i + nx*(j + ny*k)).
 * Cells are the (nx-1)(ny-1)(nz-1) cubes between grid points; a grid point is
 * inside when value >= iso, with iso rounded to float32 first. The vertex on edge
 * (lower corner value v0, upper v1) is lower + t along the edge's axis with
 * t = (iso - v0) / (v1 - v0), each operation rounded to float32 (as f32 code does),
 * and the coordinate base + t rounded to float32.
 */
export function marchingCubes(values: Float32Array, dims: Dims3, iso: number): MarchingCubesResult {
  const cells = cellCount(values, dims);
  if (cells === 0) return { positions: new Float32Array(0), triangleCount: 0 };
  const [nx, ny, nz] = dims;
  const t = fround(iso);
  const cases = new Uint8Array(cells);
  const vertexCount = classifyCells(values, nx, ny, nz, t, cases);
  const positions = new Float32Array(vertexCount * 3);
  emitVertices(values, nx, ny, nz, t, cases, positions);
  return { positions, triangleCount: vertexCount / 3 };
}

/**
 * Pass 1: the case index of every cell (x fastest) into `cases`; returns the total
 * vertex count. A cell's case is two 4-corner "columns" (x = i and x = i + 1) of
 * inside bits: the column at x holds the (y, z) offsets (0,0), (1,0), (0,1), (1,1)
 * at bits 0, 2, 4, 6, so column(i) | column(i + 1) << 1 puts corner
 * c = dx + 2dy + 4dz at bit c.
 */
function classifyCells(values: Float32Array, nx: number, ny: number, nz: number, t: number, cases: Uint8Array): number {
  const sx = nx;
  const sxy = nx * ny;
  let vertexCount = 0;
  let cell = 0;
  for (let k = 0; k < nz - 1; k++) {
    for (let j = 0; j < ny - 1; j++) {
      const r00 = j * sx + k * sxy;
      const r10 = r00 + sx;
      const r01 = r00 + sxy;
      const r11 = r01 + sx;
      let prev = (values[r00] >= t ? 1 : 0) | (values[r10] >= t ? 4 : 0) | (values[r01] >= t ? 16 : 0) | (values[r11] >= t ? 64 : 0);
      for (let i = 1; i < nx; i++) {
        const next =
          (values[r00 + i] >= t ? 1 : 0) |
          (values[r10 + i] >= t ? 4 : 0) |
          (values[r01 + i] >= t ? 16 : 0) |
          (values[r11 + i] >= t ? 64 : 0);
        const c = prev | (next << 1);
        cases[cell++] = c;
        vertexCount += CASE_VERTEX_COUNT[c];
        prev = next;
      }
    }
  }
  return vertexCount;
}

/** Pass 2: the vertices of every non-empty cell, in cell order, into `positions`. */
function emitVertices(
  values: Float32Array,
  nx: number,
  ny: number,
  nz: number,
  t: number,
  cases: Uint8Array,
  positions: Float32Array,
): void {
  const sx = nx;
  const sxy = nx * ny;
  const cornerOffset = new Int32Array(8);
  for (let c = 0; c < 8; c++) cornerOffset[c] = (c & 1) + ((c >> 1) & 1) * sx + (c >> 2) * sxy;
  const cv = new Float32Array(8);
  let out = 0;
  let cell = 0;
  for (let k = 0; k < nz - 1; k++) {
    for (let j = 0; j < ny - 1; j++) {
      for (let i = 0; i < nx - 1; i++) {
        const c = cases[cell++];
        const n = CASE_VERTEX_COUNT[c];
        if (n === 0) continue;
        const base = i + j * sx + k * sxy;
        for (let q = 0; q < 8; q++) cv[q] = values[base + cornerOffset[q]];
        const row = c * CASE_TABLE_STRIDE;
        for (let m = 0; m < n; m++) {
          const e = CASE_EDGE_TABLE[row + m];
          const lo = EDGE_LO[e];
          const v0 = cv[lo];
          const tt = fround(fround(t - v0) / fround(cv[EDGE_HI[e]] - v0));
          const x = i + (lo & 1);
          const y = j + ((lo >> 1) & 1);
          const z = k + (lo >> 2);
          // A Float32Array store rounds once: base + t rounded to float32.
          const axis = e >> 2;
          positions[out] = axis === 0 ? x + tt : x;
          positions[out + 1] = axis === 1 ? y + tt : y;
          positions[out + 2] = axis === 2 ? z + tt : z;
          out += 3;
        }
      }
    }
  }
}
