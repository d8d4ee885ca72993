// Sizes a surface can have, known before anything is read or compressed, so
// that a volume past them is refused at open with the limit named (the
// isosurface pipeline holds the same limits; src/isosurface/vertex-format.ts).

/** Bits a welded vertex has for its block's coordinates, all axes together (vertex_format.wgsl). */
export const VERTEX_BLOCK_BITS = 36;

/** Up to this many voxels on every axis, a vertex's block coordinates take 12 bits per axis (the layout every such volume has always had). */
export const MAX_VERTEX_VOXELS = 4 * 4096;

/** Voxels along one axis: vertex positions are float32, whole voxels exact up to 2^24. */
export const MAX_AXIS_VOXELS = 2 ** 24;

/** Bits that hold the coordinates 0 .. n-1 (0 for a single block). */
function bitsFor(n: number): number {
  return n <= 1 ? 0 : 32 - Math.clz32(n - 1);
}

/**
 * How a vertex's block coordinates share its 36 bits on a block grid of
 * `blocks` (blocks per axis): [x bits, y bits]; z takes the rest. 12 and 12
 * when every axis has at most 4096 blocks; otherwise as many as each axis
 * needs, so that a 131072 x 64 x 64 volume fits as well as a 16384^3 one.
 * Null when the axes need more than 36 bits together.
 */
export function vertexBlockBits(blocks: readonly number[]): [number, number] | null {
  if (blocks.every((n) => n <= 4096)) return [12, 12];
  const bits = blocks.map(bitsFor);
  return bits[0] + bits[1] + bits[2] <= VERTEX_BLOCK_BITS ? [bits[0], bits[1]] : null;
}

/** Why a volume of `dims` cannot be drawn as a surface, or null. */
export function surfaceDimsProblem(dims: readonly number[]): string | null {
  const widest = Math.max(...dims);
  if (widest > MAX_AXIS_VOXELS)
    return `${dims.join('x')} voxels: ${widest} along an axis, and a surface's vertex positions are float32, whole voxels exact up to ${MAX_AXIS_VOXELS} per axis`;
  const blocks = dims.map((d) => Math.ceil(d / 4));
  if (vertexBlockBits(blocks)) return null;
  const needs = blocks.map(bitsFor);
  return `${dims.join('x')} voxels: its ${blocks.join(' x ')} blocks of 4^3 need ${needs.join(' + ')} = ${needs[0] + needs[1] + needs[2]} bits to be numbered per axis, and a surface's vertices place their block in ${VERTEX_BLOCK_BITS} bits`;
}
