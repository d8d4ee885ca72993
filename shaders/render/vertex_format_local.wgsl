// TEMPORARY copy of the compressed vertex decode (contract in
// src/isosurface/types.ts) until shaders/isosurface/vertex_format.wgsl lands.
fn decode_vertex_position(packed: u32, block_id: u32, block_grid: vec3u) -> vec3f {
  let q = vec3u(packed & 0x3ffu, (packed >> 10u) & 0x3ffu, (packed >> 20u) & 0x3ffu);
  let bx = block_id % block_grid.x;
  let by = (block_id / block_grid.x) % block_grid.y;
  let bz = block_id / (block_grid.x * block_grid.y);
  return vec3f(f32(bx * 4u), f32(by * 4u), f32(bz * 4u)) + vec3f(q) * (4.0 / 1023.0);
}
