// The compressed vertex format (8 bytes per vertex, src/isosurface/types.ts):
// word 0 packs the position relative to the block's origin 4 * (bx, by, bz),
// quantized to 10 bits per axis, q = round(local * 1023 / 4) with local in
// [0, 4] voxels (x in bits 0-9, y in 10-19, z in 20-29); word 1 is the block
// id bx + gx * (by + gy * bz). The renderer composes this file in and calls
// decode_vertex_position; the extraction kernel calls encode_vertex_position.
//
// Normals (4 bytes per vertex, a parallel buffer per shard, written once per
// surface by the vertex pass): the unit gradient direction, octahedral-encoded
// as two 16-bit values q = 1 + round((o * 0.5 + 0.5) * 65534) (x in bits
// 0-15, y in 16-31); 0 means "no gradient" (flat shading).

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

// Octahedral encoding of a gradient (any length); 0 when it has none.
fn encode_vertex_normal(g: vec3f) -> u32 {
  let l1 = abs(g.x) + abs(g.y) + abs(g.z);
  if (!(l1 > 1e-30)) {
    return 0u;
  }
  let n = g / l1;
  var o = n.xy;
  if (n.z < 0.0) {
    o = (vec2f(1.0) - abs(n.yx)) * select(vec2f(-1.0), vec2f(1.0), n.xy >= vec2f(0.0));
  }
  let q = vec2u(round((clamp(o, vec2f(-1.0), vec2f(1.0)) * 0.5 + 0.5) * 65534.0)) + vec2u(1u);
  return q.x | (q.y << 16u);
}

// The unit normal of encode_vertex_normal, or the zero vector for 0.
fn decode_vertex_normal(packed: u32) -> vec3f {
  if (packed == 0u) {
    return vec3f(0.0);
  }
  let o = (vec2f(f32(packed & 0xffffu), f32(packed >> 16u)) - 1.0) / 65534.0 * 2.0 - 1.0;
  var n = vec3f(o, 1.0 - abs(o.x) - abs(o.y));
  if (n.z < 0.0) {
    n = vec3f((vec2f(1.0) - abs(n.yx)) * select(vec2f(-1.0), vec2f(1.0), n.xy >= vec2f(0.0)), n.z);
  }
  return normalize(n);
}
