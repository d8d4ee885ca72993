// Block naming for the ray caster (raycast.wgsl) over a volume opened
// whole: a block's id is its raster index over the block grid (x fastest),
// and the ray may enter every block.

fn block_id(b: vec3u) -> u32 {
  return b.x + rays.grid.x * (b.y + rays.grid.y * b.z);
}

// The whole volume is this draw's: traced everywhere, one box.
fn region_box(c: vec3u, lo: ptr<function, vec3f>, hi: ptr<function, vec3f>) -> bool {
  *lo = vec3f(-1e30);
  *hi = vec3f(1e30);
  return true;
}
