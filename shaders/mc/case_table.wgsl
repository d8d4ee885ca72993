// Marching-cubes conventions for kernels (src/mc/README.md). The table itself is
// the 512 u32 of packCaseTable() (src/mc/case-table.ts), bound by the kernel; pass
// a case's two words here as vec2u(table[2c], table[2c + 1]).
// Corner c = x + 2y + 4z; edge e along axis e >> 2, from its lower corner to
// lower | 1 << axis; a grid point is inside when value >= iso.

fn mc_corner_offset(c: u32) -> vec3u {
  return vec3u(c & 1u, (c >> 1u) & 1u, c >> 2u);
}

fn mc_edge_axis(e: u32) -> u32 {
  return e >> 2u;
}

// Lower corner of edge e: bits (e & 1) and (e >> 1 & 1) go to the two other axes,
// (y, z) for an x edge, (x, z) for a y edge, (x, y) for a z edge.
fn mc_edge_lower(e: u32) -> u32 {
  let axis = e >> 2u;
  let u = select(0u, 1u, axis == 0u);
  let v = select(2u, 1u, axis == 2u);
  return ((e & 1u) << u) | (((e >> 1u) & 1u) << v);
}

fn mc_edge_upper(e: u32) -> u32 {
  return mc_edge_lower(e) | (1u << (e >> 2u));
}

// Number of triangles (0..5) of a case, from its packed words.
fn mc_case_triangles(words: vec2u) -> u32 {
  return words.y >> 28u;
}

// Edge of vertex j (0..14) of a case, from its packed words.
fn mc_case_edge(words: vec2u, j: u32) -> u32 {
  return (select(words.x, words.y, j >= 8u) >> (4u * (j & 7u))) & 15u;
}

// Vertex on edge e of the cell at grid point `cell`, with v0/v1 the values at the
// edge's lower/upper corner: lower + t along the axis, t = (iso - v0) / (v1 - v0)
// measured from the lower corner, so neighbouring cells agree bit for bit.
fn mc_edge_vertex(cell: vec3u, e: u32, v0: f32, v1: f32, iso: f32) -> vec3f {
  let t = (iso - v0) / (v1 - v0);
  var p = vec3f(cell + mc_corner_offset(mc_edge_lower(e)));
  let axis = e >> 2u;
  p[axis] = p[axis] + t;
  return p;
}

// Case index of a cell's 8 corner values (indexed by corner number).
fn mc_case_index(values: array<f32, 8>, iso: f32) -> u32 {
  var v = values;
  var c = 0u;
  for (var q = 0u; q < 8u; q++) {
    c |= select(0u, 1u << q, v[q] >= iso);
  }
  return c;
}
