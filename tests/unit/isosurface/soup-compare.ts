// Triangle-for-triangle comparison of a GPU soup in the compressed vertex
// format with the serial CPU marching cubes of the same decoded volume.
//
// A welded vertex is quantized relative to the block of the cell that owns
// its edge, not necessarily the block of every triangle using it, so both
// soups are put in absolute quantized coordinates: a block is 4 voxels =
// 1023 quanta, so block b's q is 1023 * b + q. The CPU soup is quantized
// as the kernel does, relative to the block of the cell that emitted each
// triangle (the serial MC emits cells in raster order, so walking the cells'
// case vertex counts assigns every triangle its cell). The two soups are
// then compared as multisets of 3 quantized vertices, a triangle's starting
// vertex free but not its winding. Exact matches first; what is left (a
// coordinate whose local * 1023/4 sits at a rounding boundary, where float32
// rounding of block-relative vs global coordinates may differ) is matched
// with each quantized coordinate within 1, by maximum bipartite matching over
// all triangles of the regions concerned (a region: the block-sized cube
// holding a triangle's centroid), so the order of matching never matters.
import { CASE_VERTEX_COUNT, caseIndex } from '../../../src/mc/case-table.ts';
import { marchingCubes } from '../../../src/mc/serial-mc.ts';
import type { Dims } from '../../../src/core/naming.ts';

interface Tri {
  /** The region (block-sized cube) of the triangle's centroid. */
  block: string;
  q: number[]; // 9 absolute quantized coordinates, rotated to start at the smallest vertex
}

export interface BlockSoupComparison {
  trianglesGpu: number;
  trianglesCpu: number;
  exact: number;
  withinOne: number;
  unmatchedGpu: Tri[];
  unmatchedCpu: Tri[];
}

function canonical(q: number[]): Tri {
  const v = [q.slice(0, 3), q.slice(3, 6), q.slice(6, 9)];
  const block = [0, 1, 2].map((a) => Math.floor((q[a] + q[a + 3] + q[a + 6]) / 3069)).join(',');
  const less = (a: number[], b: number[]) => a[0] - b[0] || a[1] - b[1] || a[2] - b[2];
  let first = 0;
  if (less(v[1], v[first]) < 0) first = 1;
  if (less(v[2], v[first]) < 0) first = 2;
  return { block, q: [...v[first], ...v[(first + 1) % 3], ...v[(first + 2) % 3]] };
}

const key = (t: Tri) => `${t.block}:${t.q.join(',')}`;

export function gpuTriangles(packed: Uint32Array, dims: Dims): Tri[] {
  const gx = Math.ceil(dims[0] / 4);
  const gy = Math.ceil(dims[1] / 4);
  const out: Tri[] = [];
  for (let v = 0; v + 2 < packed.length / 2; v += 3) {
    const q: number[] = [];
    for (let k = 0; k < 3; k++) {
      const p = packed[2 * (v + k)];
      const b = packed[2 * (v + k) + 1];
      const c = [b % gx, Math.floor(b / gx) % gy, Math.floor(b / (gx * gy))];
      q.push((p & 1023) + 1023 * c[0], ((p >>> 10) & 1023) + 1023 * c[1], ((p >>> 20) & 1023) + 1023 * c[2]);
    }
    out.push(canonical(q));
  }
  return out;
}

/** The serial MC soup of `values` at `iso`, each triangle with its block and quantized block-relative vertices. */
export function cpuTriangles(values: Float32Array, dims: Dims, iso: number): Tri[] {
  const [nx, ny, nz] = dims;
  const { positions } = marchingCubes(values, dims, iso);
  const t = Math.fround(iso);
  const corners = new Float32Array(8);
  const out: Tri[] = [];
  let p = 0;
  for (let k = 0; k < nz - 1; k++) {
    for (let j = 0; j < ny - 1; j++) {
      for (let i = 0; i < nx - 1; i++) {
        for (let c = 0; c < 8; c++) corners[c] = values[i + (c & 1) + nx * (j + ((c >> 1) & 1) + ny * (k + (c >> 2)))];
        const n = CASE_VERTEX_COUNT[caseIndex(corners, t)];
        const origin = [4 * (i >> 2), 4 * (j >> 2), 4 * (k >> 2)];
        for (let m = 0; m < n; m += 3) {
          const q: number[] = [];
          for (let a = 0; a < 9; a++) {
            const local = Math.min(1023, Math.max(0, Math.round((positions[p + a] - origin[a % 3]) * 255.75)));
            q.push(local + (origin[a % 3] / 4) * 1023);
          }
          out.push(canonical(q));
          p += 9;
        }
      }
    }
  }
  if (p !== positions.length) throw new Error(`cell walk used ${p / 3} of ${positions.length / 3} vertices`);
  return out;
}

function withinOne(a: Tri, b: Tri): boolean {
  if (a.block !== b.block) return false;
  for (let r = 0; r < 3; r++) {
    let ok = true;
    for (let v = 0; v < 3 && ok; v++) {
      for (let c = 0; c < 3 && ok; c++) ok = Math.abs(a.q[3 * v + c] - b.q[3 * ((v + r) % 3) + c]) <= 1;
    }
    if (ok) return true;
  }
  return false;
}

/** Maximum bipartite matching (augmenting paths) between two small lists. */
function maxMatching(a: Tri[], b: Tri[]): { matchA: number[]; matched: number } {
  const adj = a.map((x) => b.map((y, j) => (withinOne(x, y) ? j : -1)).filter((j) => j >= 0));
  const matchB = new Array<number>(b.length).fill(-1);
  const matchA = new Array<number>(a.length).fill(-1);
  const tryAugment = (i: number, seen: Uint8Array): boolean => {
    for (const j of adj[i]) {
      if (seen[j]) continue;
      seen[j] = 1;
      if (matchB[j] < 0 || tryAugment(matchB[j], seen)) {
        matchB[j] = i;
        matchA[i] = j;
        return true;
      }
    }
    return false;
  };
  let matched = 0;
  for (let i = 0; i < a.length; i++) if (tryAugment(i, new Uint8Array(b.length))) matched++;
  return { matchA, matched };
}

export function compareBlockSoups(gpu: Tri[], cpu: Tri[]): BlockSoupComparison {
  const counts = new Map<string, number>();
  for (const t of cpu) counts.set(key(t), (counts.get(key(t)) ?? 0) + 1);
  const leftGpu: Tri[] = [];
  let exact = 0;
  for (const t of gpu) {
    const k = key(t);
    const n = counts.get(k) ?? 0;
    if (n > 0) {
      counts.set(k, n - 1);
      exact++;
    } else {
      leftGpu.push(t);
    }
  }
  const leftCpu: Tri[] = [];
  for (const t of cpu) {
    const k = key(t);
    const n = counts.get(k) ?? 0;
    if (n > 0) {
      counts.set(k, n - 1);
      leftCpu.push(t);
    }
  }
  // Blocks with leftovers: match all their triangles again, by maximum matching.
  const blocks = new Set([...leftGpu, ...leftCpu].map((t) => t.block));
  let withinOneCount = 0;
  const unmatchedGpu: Tri[] = [];
  const unmatchedCpu: Tri[] = [];
  for (const b of blocks) {
    const a = gpu.filter((t) => t.block === b);
    const c = cpu.filter((t) => t.block === b);
    const { matchA, matched } = maxMatching(a, c);
    const exactHere = a.length - leftGpu.filter((t) => t.block === b).length;
    withinOneCount += matched - exactHere;
    exact -= 0;
    const used = new Set(matchA.filter((j) => j >= 0));
    a.forEach((t, i) => matchA[i] < 0 && unmatchedGpu.push(t));
    c.forEach((t, j) => !used.has(j) && unmatchedCpu.push(t));
  }
  return { trianglesGpu: gpu.length, trianglesCpu: cpu.length, exact, withinOne: withinOneCount, unmatchedGpu, unmatchedCpu };
}

/**
 * Grid edges of the cells whose two ends are on different sides of `iso`
 * (value >= iso inside): the welded vertex count. A volume one voxel thin
 * on an axis has no cells, so no edges of cells.
 */
export function crossedEdges(values: Float32Array, dims: Dims, iso: number): number {
  const [nx, ny, nz] = dims;
  if (nx < 2 || ny < 2 || nz < 2) return 0;
  const t = Math.fround(iso);
  const inside = (x: number, y: number, z: number) => values[x + nx * (y + ny * z)] >= t;
  let n = 0;
  for (let z = 0; z < nz; z++)
    for (let y = 0; y < ny; y++)
      for (let x = 0; x < nx; x++) {
        const here = inside(x, y, z);
        if (x + 1 < nx && inside(x + 1, y, z) !== here) n++;
        if (y + 1 < ny && inside(x, y + 1, z) !== here) n++;
        if (z + 1 < nz && inside(x, y, z + 1) !== here) n++;
      }
  return n;
}
