// The compressed vertex format (8 bytes per vertex, src/isosurface/types.ts):
// word 0 packs the position relative to the block's origin 4 * (bx, by, bz),
// quantized to 10 bits per axis, q = round(local * 1023 / 4) with local in
// [0, 4] voxels (x in bits 0-9, y in 10-19, z in 20-29); word 1 is the block
// id bx + gx * (by + gy * bz). The renderer composes this file in and calls
// decode_vertex_position; the extraction kernel calls encode_vertex_position.

fn encode_vertex_position(local: vec3f) -> u32 {
  let q = vec3u(clamp(round(local * (1023.0 / 4.0)), vec3f(0.0), vec3f(1023.0)));
  return q.x | (q.y << 10u) | (q.z << 20u);
}

// Voxel-index-space position (voxel (i, j, k) at (i, j, k)) of a vertex.
fn decode_vertex_position(packed: u32, block_id: u32, block_grid: vec3u) -> vec3f {
  let q = vec3u(packed & 1023u, (packed >> 10u) & 1023u, (packed >> 20u) & 1023u);
  let b = vec3u(block_id % block_grid.x, (block_id / block_grid.x) % block_grid.y, block_id / (block_grid.x * block_grid.y));
  return vec3f(b * 4u) + vec3f(q) * (4.0 / 1023.0);
}
