// emit_vertices: see block_mc_common.wgsl. Needs block_mc_common.wgsl, vertex_format.wgsl.

// ---- emit_vertices: the emitting cells whose vertices reach one shard
@group(1) @binding(0) var<storage, read> cell_records: array<u32>;
@group(1) @binding(1) var<storage, read> cell_first: array<u32>;
@group(2) @binding(0) var<storage, read> shard: array<u32, 8>;        // this shard's record (plan.wgsl)
@group(2) @binding(1) var<storage, read_write> shard_vertices: array<vec2u>;
@group(2) @binding(2) var<storage, read_write> shard_normals: array<u32>;

// Normals, once per surface (the renderer reads them, nothing per frame): the
// central-difference gradient at both ends of the vertex's edge, interpolated
// at the vertex -- the gradient VTK's ComputeNormals gives. A neighbour voxel
// outside the volume or in a block not cached gives a one-sided difference.
// The gradients are taken once per cell at its 8 corners: along each axis one
// neighbour of a corner is another corner (already read), so a cell reads 24
// voxels more, whatever its number of vertices.
// The voxel at global grid point g: (value, 1) when it is readable, (0, 0) otherwise.
fn grid_voxel(g: vec3i) -> vec2f {
  if (any(g < vec3i(0)) || any(g >= vec3i(volume.dims))) {
    return vec2f(0.0);
  }
  let slot = block_to_slot[block_index_of(vec3u(g) >> vec3u(2u), volume.grid)];
  if (slot == NONE) {
    return vec2f(0.0);
  }
  let v = vec3u(g) & vec3u(3u);
  return vec2f(slot_rows[slot * 16u + v.y + 4u * v.z][v.x], 1.0);
}

@compute @workgroup_size(64)
fn emit_vertices(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                 @builtin(local_invocation_index) lid: u32) {
  let k = grid_invocation_index(wid, nwg, lid, 64u);
  if (k >= shard[S_COUNT]) {
    return;
  }
  let j = shard[S_FIRST] + k;
  let record = cell_records[j];
  let first = cell_first[j];
  let b = active_ids[record >> 6u];
  let l = cell_of(record & 63u);
  let c = block_coords_of(b, volume.grid);
  let own = block_to_slot[b];
  // The 8 corners (q = x + 2y + 4z); every block the cell touches is cached.
  var values: array<f32, 8>;
  var code = 0u;
  for (var q = 0u; q < 8u; q++) {
    let p = l + mc_corner_offset(q);
    let d = p >> vec3u(2u);
    var slot = own;
    if (any(d != vec3u(0u))) {
      slot = block_to_slot[block_index_of(c + d, volume.grid)];
    }
    let v = p & vec3u(3u);
    let value = slot_rows[slot * 16u + v.y + 4u * v.z][v.x];
    values[q] = value;
    code |= select(0u, 1u << q, value >= volume.iso);
  }
  let words = case_words(code);
  let n = 3u * mc_case_triangles(words);
  // Corner gradients (corner q at global grid point origin + offset(q)).
  let origin = vec3i(c * 4u + l);
  var grads: array<vec3f, 8>;
  for (var q = 0u; q < 8u; q++) {
    let o = mc_corner_offset(q);
    let g = origin + vec3i(o);
    var d = vec3f(0.0);
    for (var a = 0u; a < 3u; a++) {
      let inner = values[q ^ (1u << a)];
      var step = vec3i(0);
      step[a] = select(-1, 1, o[a] == 1u);
      let outer = grid_voxel(g + step);
      // bit 0: inner is at +1, outer at -1; bit 1: the other way round
      let sign = select(1.0, -1.0, o[a] == 1u);
      if (outer.y > 0.0) {
        d[a] = 0.5 * sign * (inner - outer.x);
      } else {
        d[a] = sign * (inner - values[q]);
      }
    }
    grads[q] = d;
  }
  let base = shard[S_BASE];
  let size = arrayLength(&shard_vertices);
  for (var m = 0u; m < n; m++) {
    let v = first + m;
    if (v < base || v - base >= size) {
      continue;
    }
    let e = mc_case_edge(words, m);
    let lower = mc_edge_lower(e);
    let v0 = values[lower];
    let v1 = values[mc_edge_upper(e)];
    // the project's interpolation formula (src/mc/README.md), from the lower corner
    let t = (volume.iso - v0) / (v1 - v0);
    var p = vec3f(l + mc_corner_offset(lower));
    let axis = mc_edge_axis(e);
    p[axis] = p[axis] + t;
    shard_vertices[v - base] = vec2u(encode_vertex_position(p), b);
    // Outward (toward decreasing values): minus the gradient.
    shard_normals[v - base] = encode_vertex_normal(-mix(grads[lower], grads[mc_edge_upper(e)], t));
  }
}
