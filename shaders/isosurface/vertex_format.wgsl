// The compressed vertex format (12 bytes per welded vertex, src/isosurface/types.ts).
// Every vertex lies on a cut grid edge, so it is written as that edge and a
// fraction along it, and its block by its coordinates (not a raster id, so
// levels of any block count place vertices alike):
//   word 0: the edge's lower corner relative to the block's origin, 0..4 per
//           axis (bits 0-2 x, 3-5 y, 6-8 z), the edge's axis (bits 9-10), the
//           fraction t along it quantized to 16 bits (11-26: round(t * 65535)),
//           and bits 32-35 of the block field (27-30)
//   word 1: bits 0-31 of the block field
//   word 2: the normal (below)
// The block field is 36 bits: bx, then by, then bz, each as wide as the
// volume's block grid needs (vertex_block_bits): 12 bits each up to 4096
// blocks per axis (16384 voxels), otherwise the bits of each axis's block
// count, so a 131072 x 64 x 64 volume fits as a 16384^3 one does (larger
// ones are refused at open: surfaceDimsProblem in src/core/limits.ts). The
// renderer composes this file in and calls decode_vertex_position; the
// extraction kernel calls encode_vertex_edge. Both pass the block grid.

// Bits that hold 0 .. n-1.
fn vertex_bits_for(n: u32) -> u32 {
  return select(0u, 32u - countLeadingZeros(n - 1u), n > 1u);
}

// (x bits, y bits) of the block field on a block grid; z has the rest (src/core/limits.ts twin).
fn vertex_block_bits(grid: vec3u) -> vec2u {
  if (all(grid <= vec3u(4096u))) {
    return vec2u(12u, 12u);
  }
  return vec2u(vertex_bits_for(grid.x), vertex_bits_for(grid.y));
}

// `v` shifted left by `s` (< 36) as the (low, high) words of the block field.
fn vertex_field_shl(v: u32, s: u32) -> vec2u {
  if (s == 0u) {
    return vec2u(v, 0u);
  }
  if (s >= 32u) {
    return vec2u(0u, v << (s - 32u));
  }
  return vec2u(v << s, v >> (32u - s));
}

// `k` bits from bit `s` of the block field (low, high).
fn vertex_field_bits(lo: u32, hi: u32, s: u32, k: u32) -> u32 {
  var v: u32;
  if (s == 0u) {
    v = lo;
  } else if (s >= 32u) {
    v = hi >> (s - 32u);
  } else {
    v = (lo >> s) | (hi << (32u - s));
  }
  return select(v & ((1u << k) - 1u), v, k >= 32u);
}

fn encode_vertex_edge(corner: vec3u, axis: u32, t: f32, block: vec3u, grid: vec3u) -> vec2u {
  let q = u32(round(clamp(t, 0.0, 1.0) * 65535.0));
  let k = vertex_block_bits(grid);
  let field = vec2u(block.x, 0u) | vertex_field_shl(block.y, k.x) | vertex_field_shl(block.z, k.x + k.y);
  let w0 = corner.x | (corner.y << 3u) | (corner.z << 6u) | (axis << 9u) | (q << 11u) | ((field.y & 15u) << 27u);
  return vec2u(w0, field.x);
}

// The block coordinates of a vertex's words on a block grid.
fn decode_vertex_block(w0: u32, w1: u32, grid: vec3u) -> vec3u {
  let k = vertex_block_bits(grid);
  let hi = (w0 >> 27u) & 15u;
  return vec3u(
    vertex_field_bits(w1, hi, 0u, k.x),
    vertex_field_bits(w1, hi, k.x, k.y),
    vertex_field_bits(w1, hi, k.x + k.y, 36u - k.x - k.y),
  );
}

// Voxel-index-space position (voxel (i, j, k) at (i, j, k)) of a vertex of a volume of `grid` blocks.
fn decode_vertex_position(w0: u32, w1: u32, grid: vec3u) -> vec3f {
  let block = decode_vertex_block(w0, w1, grid);
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
