// The compressed vertex format on the CPU (the WGSL side is
// shaders/isosurface/vertex_format.wgsl): a welded vertex is 3 u32, its cut
// edge (lower corner relative to the block origin, axis) and the fraction
// along it in 16 bits, its block's coordinates (a 36-bit field, each axis as
// wide as the volume's block grid needs: 12 bits each up to 4096 blocks per
// axis), and the normal.
import { vertexBlockBits } from '../core/limits.ts';
import type { SurfaceMesh } from './types.ts';

/** Voxels per quantization step along an edge: 1 / 65535. */
export const VERTEX_QUANTUM = 1 / 65535;

/** Up to this many voxels on every axis, block coordinates have 12 bits per axis; wider volumes share the 36 bits by need (core/limits.ts, so that opening can check it). */
export { MAX_VERTEX_VOXELS, VERTEX_BLOCK_BITS } from '../core/limits.ts';

/** A volume's voxel dims; without them, the 12-bit-per-axis layout of volumes of at most 16384 voxels per axis. */
type Dims = readonly number[] | undefined;

/** [x bits, y bits] of the block field of a volume of `dims` voxels (z has the rest). */
function fieldBits(dims: Dims): [number, number] {
  if (!dims) return [12, 12];
  const bits = vertexBlockBits(dims.map((d) => Math.ceil(d / 4)));
  if (!bits) throw new RangeError(`${dims.join('x')} voxels: too many blocks for a vertex's 36-bit block field`);
  return bits;
}

/** The two position words of the vertex on the edge from `corner` (0..4 per axis, block-relative) along `axis` at fraction `t`, in `block`, of a volume of `dims` voxels. */
export function encodeVertexEdge(
  corner: readonly [number, number, number],
  axis: number,
  t: number,
  block: readonly [number, number, number],
  dims?: readonly number[],
): [number, number] {
  const [kx, ky] = fieldBits(dims);
  const q = roundHalfEven(Math.fround(Math.min(1, Math.max(0, t)) * 65535));
  // the field below 2^36: exact in a double
  const field = block[0] + block[1] * 2 ** kx + block[2] * 2 ** (kx + ky);
  const hi = Math.floor(field / 2 ** 32);
  const w0 = corner[0] | (corner[1] << 3) | (corner[2] << 6) | (axis << 9) | (q << 11) | ((hi & 15) << 27);
  return [w0 >>> 0, (field % 2 ** 32) >>> 0];
}

/** WGSL's round(): halfway cases to even. */
function roundHalfEven(x: number): number {
  const r = Math.round(x);
  return r - x === 0.5 && r % 2 !== 0 ? r - 1 : r;
}

/** The block coordinates of a vertex's words, in a volume of `dims` voxels. */
export function vertexBlock(w0: number, w1: number, dims?: readonly number[]): [number, number, number] {
  const [kx, ky] = fieldBits(dims);
  const field = ((w0 >>> 27) & 15) * 2 ** 32 + (w1 >>> 0);
  const x = field % 2 ** kx;
  const y = Math.floor(field / 2 ** kx) % 2 ** ky;
  return [x, y, Math.floor(field / 2 ** (kx + ky))];
}

/**
 * Decodes `count` vertices into voxel index space positions (xyz per
 * vertex): 4 * block + corner, plus the fraction along the edge's axis.
 * `stride`: u32 per vertex (3 for welded vertices, whose third word is the
 * normal; 2 for position words alone). `dims`: the volume's voxels (how the
 * block field is laid out; needed past 16384 voxels on an axis).
 */
export function decodeVertices(packed: Uint32Array, count: number, stride = 3, dims?: readonly number[]): Float32Array {
  if (packed.length < stride * count)
    throw new Error(`decodeVertices: ${count} vertices need ${stride * count} words, got ${packed.length}`);
  const out = new Float32Array(3 * count);
  for (let v = 0; v < count; v++) {
    const w0 = packed[stride * v];
    const w1 = packed[stride * v + 1];
    const b = vertexBlock(w0, w1, dims);
    out[3 * v] = 4 * b[0] + (w0 & 7);
    out[3 * v + 1] = 4 * b[1] + ((w0 >>> 3) & 7);
    out[3 * v + 2] = 4 * b[2] + ((w0 >>> 6) & 7);
    out[3 * v + ((w0 >>> 9) & 3)] += ((w0 >>> 11) & 65535) / 65535;
  }
  return out;
}

/** A read-back mesh's welded vertices as voxel index space positions (xyz per vertex). */
export function meshPositions(mesh: SurfaceMesh): Float32Array {
  return decodeVertices(mesh.vertices, mesh.vertices.length / 3, 3, mesh.dims);
}
