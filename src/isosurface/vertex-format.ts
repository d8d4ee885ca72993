// The compressed vertex format on the CPU (the WGSL side is
// shaders/isosurface/vertex_format.wgsl): a welded vertex is 3 u32, its cut
// edge (lower corner relative to the block origin, axis) and the fraction
// along it in 16 bits, its block's coordinates (12 bits per axis), and the
// normal.

/** Voxels per quantization step along an edge: 1 / 65535. */
export const VERTEX_QUANTUM = 1 / 65535;

/** Block coordinates have 12 bits per axis: at most this many voxels per axis (core/limits.ts, so that opening can check it). */
export { MAX_VERTEX_VOXELS } from '../core/limits.ts';

/** The two position words of the vertex on the edge from `corner` (0..4 per axis, block-relative) along `axis` at fraction `t`, in `block`. */
export function encodeVertexEdge(
  corner: readonly [number, number, number],
  axis: number,
  t: number,
  block: readonly [number, number, number],
): [number, number] {
  const q = roundHalfEven(Math.fround(Math.min(1, Math.max(0, t)) * 65535));
  const w0 = corner[0] | (corner[1] << 3) | (corner[2] << 6) | (axis << 9) | (q << 11) | ((block[2] >> 8) << 27);
  const w1 = block[0] | (block[1] << 12) | ((block[2] & 255) << 24);
  return [w0 >>> 0, w1 >>> 0];
}

/** WGSL's round(): halfway cases to even. */
function roundHalfEven(x: number): number {
  const r = Math.round(x);
  return r - x === 0.5 && r % 2 !== 0 ? r - 1 : r;
}

/** The block coordinates of a vertex's words. */
export function vertexBlock(w0: number, w1: number): [number, number, number] {
  return [w1 & 4095, (w1 >>> 12) & 4095, (w1 >>> 24) | (((w0 >>> 27) & 15) << 8)];
}

/**
 * Decodes `count` vertices into voxel index space positions (xyz per
 * vertex): 4 * block + corner, plus the fraction along the edge's axis.
 * `stride`: u32 per vertex (3 for welded vertices, whose third word is the
 * normal; 2 for position words alone).
 */
export function decodeVertices(packed: Uint32Array, count: number, stride = 3): Float32Array {
  if (packed.length < stride * count)
    throw new Error(`decodeVertices: ${count} vertices need ${stride * count} words, got ${packed.length}`);
  const out = new Float32Array(3 * count);
  for (let v = 0; v < count; v++) {
    const w0 = packed[stride * v];
    const w1 = packed[stride * v + 1];
    const b = vertexBlock(w0, w1);
    out[3 * v] = 4 * b[0] + (w0 & 7);
    out[3 * v + 1] = 4 * b[1] + ((w0 >>> 3) & 7);
    out[3 * v + 2] = 4 * b[2] + ((w0 >>> 6) & 7);
    out[3 * v + ((w0 >>> 9) & 3)] += ((w0 >>> 11) & 65535) / 65535;
  }
  return out;
}
