// The compressed vertex format (12 bytes per welded vertex, src/isosurface/types.ts).
// Every vertex lies on a cut grid edge, so it is written as that edge and a
// fraction along it, and its block by its coordinates (not a raster id, so
// levels of any block count place vertices alike):
//   word 0: the edge's lower corner relative to the block's origin, 0..4 per
//           axis (bits 0-2 x, 3-5 y, 6-8 z), the edge's axis (bits 9-10), the
//           fraction t along it quantized to 16 bits (11-26: round(t * 65535)),
//           and bits 8-11 of the block's z (27-30)
//   word 1: the block's coordinates bx (bits 0-11), by (12-23), bits 0-7 of bz (24-31)
//   word 2: the normal (below)
// Block coordinates have 12 bits per axis: volumes of up to 16384 voxels per
// axis (MAX_VERTEX_VOXELS in vertex-format.ts; larger ones are refused when
// a pipeline is made). The renderer composes this file in and calls
// decode_vertex_position; the extraction kernel calls encode_vertex_edge.

fn encode_vertex_edge(corner: vec3u, axis: u32, t: f32, block: vec3u) -> vec2u {
  let q = u32(round(clamp(t, 0.0, 1.0) * 65535.0));
  let w0 = corner.x | (corner.y << 3u) | (corner.z << 6u) | (axis << 9u) | (q << 11u) | ((block.z >> 8u) << 27u);
  let w1 = block.x | (block.y << 12u) | ((block.z & 255u) << 24u);
  return vec2u(w0, w1);
}

// Voxel-index-space position (voxel (i, j, k) at (i, j, k)) of a vertex.
fn decode_vertex_position(w0: u32, w1: u32) -> vec3f {
  let block = vec3u(w1 & 4095u, (w1 >> 12u) & 4095u, (w1 >> 24u) | (((w0 >> 27u) & 15u) << 8u));
  let corner = vec3u(w0 & 7u, (w0 >> 3u) & 7u, (w0 >> 6u) & 7u);
  var p = vec3f(block * 4u + corner);
  p[(w0 >> 9u) & 3u] += f32((w0 >> 11u) & 65535u) / 65535.0;
  return p;
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
