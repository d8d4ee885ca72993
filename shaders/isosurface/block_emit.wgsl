// emit_surface: see block_mc_common.wgsl. Needs block_mc_common.wgsl, vertex_format.wgsl, edge_owner.wgsl.

// ---- emit_surface: the emitting cells whose triangle corners reach one index shard
// The slot data voxel by voxel: voxel (x, y, z) of slot s is s * 64 + x + 4y + 16z (the
// same buffer classify reads as rows; scalar reads measured about 3% faster here on SwiftShader).
@group(0) @binding(2) var<storage, read> slot_voxels: array<f32>;
@group(1) @binding(0) var<storage, read> cell_list: array<vec2u>;   // (entry << 6 | cell | CELL_NO_INDICES?, first index)
@group(1) @binding(1) var<storage, read> slot_mc: array<vec2u>;     // per slot and row: (4 case bytes, row base)
@group(2) @binding(0) var<uniform> shard: array<vec4u, 2>;          // this shard's record (plan.wgsl): first, count, base
@group(2) @binding(1) var<storage, read_write> shard_indices: array<u32>;
// Welded vertices, 3 words each: the edge and the fraction along it, the block's coordinates, the normal (vertex_format.wgsl).
@group(2) @binding(2) var<storage, read_write> vertex_data: array<u32>;

// Normals, once per surface (the renderer reads them, nothing per frame): the
// central-difference gradient at both ends of the vertex's edge, interpolated
// at the vertex -- the gradient VTK's ComputeNormals gives. A neighbour voxel
// outside the volume or in a block not cached gives a one-sided difference.
// The voxel at global grid point g: (value, 1) when it is readable, (0, 0) otherwise.
fn grid_voxel(g: vec3i) -> vec2f {
  if (any(g < vec3i(0)) || any(g >= vec3i(volume.dims))) {
    return vec2f(0.0);
  }
  let slot = cached_slot_at(vec3u(g) >> vec3u(2u));
  if (slot == NONE) {
    return vec2f(0.0);
  }
  let v = vec3u(g) & vec3u(3u);
  return vec2f(slot_voxels[slot * 64u + v.x + 4u * v.y + 16u * v.z], 1.0);
}

// Gradient at corner q of the cell whose corner 0 is at global grid point
// `origin`: along each axis one neighbour is another corner (already read).
fn corner_gradient(values: ptr<function, array<f32, 8>>, origin: vec3i, q: u32) -> vec3f {
  let o = mc_corner_offset(q);
  let g = origin + vec3i(o);
  var d = vec3f(0.0);
  for (var a = 0u; a < 3u; a++) {
    let inner = (*values)[q ^ (1u << a)];
    var step = vec3i(0);
    step[a] = select(-1, 1, o[a] == 1u);
    let outer = grid_voxel(g + step);
    // inner is at +1 and outer at -1 when the corner is on the cell's lower side
    let sign = select(1.0, -1.0, o[a] == 1u);
    if (outer.y > 0.0) {
      d[a] = 0.5 * sign * (inner - outer.x);
    } else {
      d[a] = sign * (inner - (*values)[q]);
    }
  }
  return d;
}

@compute @workgroup_size(64)
fn emit_surface(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                @builtin(local_invocation_index) lid: u32) {
  let k = grid_invocation_index(wid, nwg, lid, 64u);
  let record = shard[0];
  if (k >= record[S_COUNT]) {
    return;
  }
  let entry = cell_list[record[S_FIRST] + k];
  let first = entry.y;
  let b = active_ids[(entry.x & ~CELL_NO_INDICES) >> 6u];
  let l = cell_of(entry.x & 63u);
  let c = block_coords(b, volume.grid);
  let own = block_to_slot[b];
  // The 8 corners (q = x + 2y + 4z) and their blocks' slots; every block the cell touches is cached.
  var values: array<f32, 8>;
  var slots: array<u32, 8>;
  for (var q = 0u; q < 8u; q++) {
    let p = l + mc_corner_offset(q);
    let d = p >> vec3u(2u);
    var slot = own;
    if (any(d != vec3u(0u))) {
      slot = cached_slot_at(c + d);
    }
    slots[q] = slot;
    let v = p & vec3u(3u);
    values[q] = slot_voxels[slot * 64u + v.x + 4u * v.y + 16u * v.z];
  }
  let own_row = slot_mc[16u * own + l.y + 4u * l.z];
  let code = (own_row.x >> (8u * l.x)) & 255u;
  let words = case_words(code);
  // a cell without indices writes its owned vertices only (block_mc_common.wgsl)
  let n = select(3u * mc_case_triangles(words), 0u, (entry.x & CELL_NO_INDICES) != 0u);
  let g = c * 4u + l;
  let last = last_cell_axes(g, volume.dims);
  let cut = mc_cut_edges(code);
  let base = record[S_BASE];

  // The vertices this cell owns, written once: by the shard whose vertex
  // range holds its first index (plan_vertices: the shard holding that index,
  // or the last shard in use for a cell without indices at the surface's end).
  let size = arrayLength(&shard_indices);
  var owned = owned_edges(last) & cut;
  if (first >= base && first < record[S_VERTEX_END] && owned != 0u) {
    var vertex = own_row.y +
      owned_vertices_before(own_row.x, l.x, 0u, g - vec3u(l.x, 0u, 0u), volume.dims);
    let capacity = arrayLength(&vertex_data) / 3u;
    let origin = vec3i(g);
    // Every edge an inner cell owns starts at corner 0: its gradient once.
    let gradient0 = corner_gradient(&values, origin, 0u);
    while (owned != 0u) {
      let e = firstTrailingBit(owned);
      owned &= owned - 1u;
      let lower = mc_edge_lower(e);
      let upper = mc_edge_upper(e);
      let v0 = values[lower];
      let v1 = values[upper];
      // the project's interpolation formula (src/mc/README.md), from the lower corner
      let t = (volume.iso - v0) / (v1 - v0);
      if (vertex < capacity) {
        let w = encode_vertex_edge(l + mc_corner_offset(lower), mc_edge_axis(e), t, c, volume.grid);
        vertex_data[3u * vertex] = w.x;
        vertex_data[3u * vertex + 1u] = w.y;
        // Outward (toward decreasing values): minus the gradient.
        var lower_gradient = gradient0;
        if (lower != 0u) {
          lower_gradient = corner_gradient(&values, origin, lower);
        }
        let gradient = mix(lower_gradient, corner_gradient(&values, origin, upper), t);
        vertex_data[3u * vertex + 2u] = encode_vertex_normal(-gradient);
      }
      vertex += 1u;
    }
  }

  // Each triangle corner: the vertex of its edge, numbered by the edge's owner
  // (this cell or a neighbour at one of its corners: same window of blocks).
  for (var m = 0u; m < n; m++) {
    let v = first + m;
    if (v < base || v - base >= size) {
      continue;
    }
    let e = mc_case_edge(words, m);
    let lower = mc_edge_lower(e);
    // the owner's corner 0 is the edge's lower end, moved down on the axes where this cell is last
    let at = lower & ~last;
    let edge = mc_edge_of(mc_edge_axis(e), lower & last);
    let p = l + mc_corner_offset(at);
    let owner_slot = slots[at];
    let local = p & vec3u(3u);
    let row = local.y + 4u * local.z;
    let owner_row = slot_mc[16u * owner_slot + row];
    let index = owner_row.y +
      owned_vertices_before(owner_row.x, local.x, (1u << edge) - 1u, g + mc_corner_offset(at) - vec3u(local.x, 0u, 0u), volume.dims);
    shard_indices[v - base] = index;
  }
}
