// The compressed vertex format on the CPU (the WGSL side is
// shaders/isosurface/vertex_format.wgsl): 2 u32 per vertex, the position
// relative to the block origin quantized to 10 bits per axis, and the block id.
import type { Dims } from '../core/naming.ts';

/** Voxels per quantization step: 4 / 1023. */
export const VERTEX_QUANTUM = 4 / 1023;

/** Packs a position relative to its block's origin (each axis in [0, 4]) as the kernel does. */
export function encodeVertexPosition(local: readonly [number, number, number]): number {
  let packed = 0;
  for (let a = 0; a < 3; a++) {
    const q = Math.min(1023, Math.max(0, roundHalfEven(Math.fround(local[a] * 255.75))));
    packed |= q << (10 * a);
  }
  return packed >>> 0;
}

/** WGSL's round(): halfway cases to even. */
function roundHalfEven(x: number): number {
  const r = Math.round(x);
  return r - x === 0.5 && r % 2 !== 0 ? r - 1 : r;
}

/**
 * Decodes `count` vertices of packed (position, block id) pairs into voxel
 * index space positions (xyz per vertex): 4 * block coordinates + q * 4 / 1023.
 * `stride`: u32 per vertex (2 for a soup of pairs, 3 for welded vertices,
 * whose third word is the normal).
 */
export function decodeVertices(packed: Uint32Array, count: number, info: { blockGrid: Dims }, stride = 2): Float32Array {
  if (packed.length < stride * count)
    throw new Error(`decodeVertices: ${count} vertices need ${stride * count} words, got ${packed.length}`);
  const [gx, gy] = info.blockGrid;
  const out = new Float32Array(3 * count);
  for (let v = 0; v < count; v++) {
    const p = packed[stride * v];
    const b = packed[stride * v + 1];
    const bx = b % gx;
    const by = Math.floor(b / gx) % gy;
    const bz = Math.floor(b / (gx * gy));
    out[3 * v] = 4 * bx + (p & 1023) * VERTEX_QUANTUM;
    out[3 * v + 1] = 4 * by + ((p >>> 10) & 1023) * VERTEX_QUANTUM;
    out[3 * v + 2] = 4 * bz + ((p >>> 20) & 1023) * VERTEX_QUANTUM;
  }
  return out;
}
