// The page's own bricks of a store of lossless chunks (source-store.ts):
// their edge per level. The converter's --ranges-only has the same rule
// (converter/zfpzarr/ranges_only.py brick_edge): a sidecar fits the store.

/** Bricks cut from chunks that are not C^3 cubes with C a multiple of 4. */
export const BRICK_EDGE = 64;

/**
 * The brick edge of a level: its chunk edge when chunks are cubes of 4..256
 * (a multiple of 4), else BRICK_EDGE; but when the next finer level's bricks
 * (`finer`, with the level scales of both) would not nest in this level's
 * (a coarse brick made of whole finer ones on every axis, as the view's cut
 * needs to refine it), the finer level's edge, which always nests (a level
 * spans a power of two of the finer level's voxels per axis).
 */
export function brickEdge(
  chunkXYZ: readonly [number, number, number],
  scale: readonly [number, number, number],
  finer?: { edge: number; scale: readonly [number, number, number] },
): number {
  const [cx, cy, cz] = chunkXYZ;
  const cube = cx === cy && cy === cz && cx % 4 === 0 && cx >= 4 && cx <= 256;
  const edge = cube ? cx : BRICK_EDGE;
  if (!finer) return edge;
  const nests = scale.every((f, a) => (edge * f) % (finer.edge * finer.scale[a]) === 0);
  return nests ? edge : finer.edge;
}
