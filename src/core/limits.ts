// Sizes a surface can have, known before anything is read or compressed, so
// that a volume past them is refused at open with the limit named (the
// isosurface pipeline holds the same limits; src/isosurface/vertex-format.ts).

/** A welded vertex places its block with 12 bits per axis (vertex_format.wgsl): at most this many voxels along an axis. */
export const MAX_VERTEX_VOXELS = 4 * 4096;

/** Why a volume of `dims` cannot be drawn as a surface, or null. */
export function surfaceDimsProblem(dims: readonly number[]): string | null {
  const widest = Math.max(...dims);
  if (widest <= MAX_VERTEX_VOXELS) return null;
  return `${dims.join('x')} voxels: ${widest} along an axis, and a surface's vertices place their blocks with 12 bits per axis, so a volume may have at most ${MAX_VERTEX_VOXELS} voxels along an axis`;
}
