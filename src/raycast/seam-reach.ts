// How far a coarser level's rays trace into a finer region at a seam of a
// nested cut for rays (issue 46): the rule the ray caster applies
// (shaders/render/ray_blocks_pool.wgsl, region_box, given these terms by
// render/ray-layer.ts) and the rays' guidance follows (store/view/seen.ts).

/**
 * How far below a region it owns (level-0 voxels, per axis) a coarser level's
 * rays trace into a finer region in a nested cut, `scale` the coarser level's
 * voxel in level-0 voxels: the finer level stops at its chunk's last voxel,
 * at most (s_f + 1) / 2 below the face, and the coarser cell holding that
 * point starts at most one coarse voxel further down; s_f <= s / 2, and 1/4
 * of a voxel keeps the boundary tests off the seam.
 */
export const finerReachVoxels = (scale: number): number => FINER_REACH_PER_VOXEL * scale + FINER_REACH_MARGIN;

/** finerReachVoxels' terms, as the ray caster's uniforms pass them. */
export const FINER_REACH_PER_VOXEL = 1.5;
export const FINER_REACH_MARGIN = 0.25;
