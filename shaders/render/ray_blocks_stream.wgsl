// Block naming for the ray caster (raycast.wgsl) over a volume opened
// whole: a block's id is its raster index over the block grid (x fastest),
// and the ray may enter every block.

fn block_id(b: vec3u) -> u32 {
  return b.x + rays.grid.x * (b.y + rays.grid.y * b.z);
}

// Blocks (per edge) of the aligned region around b the ray skips whole: never (0).
fn region_skip(b: vec3u) -> u32 {
  return 0u;
}

// Never called: region_skip is never partial.
fn cell_outside(c: vec3u) -> bool {
  return false;
}
