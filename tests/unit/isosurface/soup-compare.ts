// Triangle-for-triangle comparison of a GPU soup in the compressed vertex
// format with the serial CPU marching cubes of the same decoded volume.
//
// A welded vertex is its grid edge and the fraction along it in 16 bits, so
// both soups are put in absolute quantized coordinates, 65535 quanta per
// voxel: the GPU's is (4 * block + corner) * 65535 (+ the fraction's 16 bits
// on the edge's axis), the CPU's is each coordinate * 65535, rounded. The two
// soups are then compared as multisets of 3 quantized vertices, a triangle's
// starting vertex free but not its winding. Exact matches first; what is
// left (float32 rounding of the fraction or of the CPU's coordinates moves a
// value by a quantum) is matched with each quantized coordinate within 1, by
// maximum bipartite matching over all triangles of the regions concerned (a
// region: the block-sized cube holding a triangle's centroid), so the order
// of matching never matters.
import { marchingCubes } from '../../../src/mc/serial-mc.ts';
import type { Dims } from '../../../src/core/naming.ts';
import { vertexBlock } from '../../../src/isosurface/vertex-format.ts';

/** Quanta per voxel. */
const Q = 65535;

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
  const block = [0, 1, 2].map((a) => Math.floor((q[a] + q[a + 3] + q[a + 6]) / (3 * 4 * Q))).join(',');
  const less = (a: number[], b: number[]) => a[0] - b[0] || a[1] - b[1] || a[2] - b[2];
  let first = 0;
  if (less(v[1], v[first]) < 0) first = 1;
  if (less(v[2], v[first]) < 0) first = 2;
  return { block, q: [...v[first], ...v[(first + 1) % 3], ...v[(first + 2) % 3]] };
}

const key = (t: Tri) => `${t.block}:${t.q.join(',')}`;

/** The GPU soup (position word pairs, 2 u32 per corner) as quantized triangles. */
export function gpuTriangles(packed: Uint32Array, _dims?: Dims): Tri[] {
  const out: Tri[] = [];
  for (let v = 0; v + 2 < packed.length / 2; v += 3) {
    const q: number[] = [];
    for (let k = 0; k < 3; k++) {
      const w0 = packed[2 * (v + k)];
      const b = vertexBlock(w0, packed[2 * (v + k) + 1]);
      const corner = [w0 & 7, (w0 >>> 3) & 7, (w0 >>> 6) & 7];
      const axis = (w0 >>> 9) & 3;
      for (let a = 0; a < 3; a++) q.push((4 * b[a] + corner[a]) * Q + (a === axis ? (w0 >>> 11) & 65535 : 0));
    }
    out.push(canonical(q));
  }
  return out;
}

/** The serial MC soup of `values` at `iso`, quantized like the GPU's. */
export function cpuTriangles(values: Float32Array, dims: Dims, iso: number): Tri[] {
  const { positions } = marchingCubes(values, dims, iso);
  const out: Tri[] = [];
  for (let p = 0; p < positions.length; p += 9) {
    const q: number[] = [];
    for (let a = 0; a < 9; a++) q.push(Math.round(positions[p + a] * Q));
    out.push(canonical(q));
  }
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
