// Block marching cubes through workgroup memory (DESIGN.md step 4): the
// workgroup loads the block and its +x/+y/+z face, edge and corner neighbour
// voxels (5 x 5 x 5 values) from the cache into workgroup memory, so each
// value is read from the cache once. Needs block_mc_common.wgsl.

var<workgroup> voxels: array<f32, 125>;          // (x, y, z) in 0..4 at x + 5y + 25z
var<workgroup> neighbour_cached: array<u32, 8>;  // block + (dx, dy, dz) cached, at dx + 2dy + 4dz

// Loads block b's 5^3 neighbourhood; call from every invocation, then barrier.
fn load_block(b: u32, lid: u32) {
  let c = block_coords_of(b, volume.grid);
  for (var s = lid; s < 125u; s += 64u) {
    let v = vec3u(s % 5u, (s / 5u) % 5u, s / 25u);
    let d = v >> vec3u(2u);              // which neighbour: 0 or 1 per axis
    let nc = c + d;
    var slot = NONE;
    if (all(nc < volume.grid)) {
      slot = block_to_slot[block_index_of(nc, volume.grid)];
    }
    var value = 0.0;
    if (slot != NONE) {
      let l = v & vec3u(3u);
      value = slot_data[slot * 64u + l.x + 4u * l.y + 16u * l.z];
    }
    voxels[s] = value;
    // exactly one invocation loads the neighbour's voxel (0, 0, 0)
    if (all((v & vec3u(3u)) == vec3u(0u))) {
      neighbour_cached[d.x + 2u * d.y + 4u * d.z] = select(0u, 1u, slot != NONE);
    }
  }
}

// Cell `l` of block b from the loaded neighbourhood.
fn load_cell(b: u32, l: vec3u) -> Cell {
  var cell: Cell;
  for (var q = 0u; q < 8u; q++) {
    let p = l + mc_corner_offset(q);
    cell.values[q] = voxels[p.x + 5u * p.y + 25u * p.z];
  }
  cell.case_index = 0u;
  if (!cell_inside_volume(block_coords_of(b, volume.grid), l)) {
    return cell;
  }
  // blocks touched: + (dx, dy, dz) with d <= reach on each axis
  let reach = vec3u(l == vec3u(3u));
  for (var d = 1u; d < 8u; d++) {
    let dd = vec3u(d & 1u, (d >> 1u) & 1u, d >> 2u);
    if (all(dd <= reach) && neighbour_cached[d] == 0u) {
      return cell;
    }
  }
  cell.case_index = case_of(cell.values);
  return cell;
}

// ---- Pass 1: vertices per active block (0 = not occupied).
@group(1) @binding(0) var<storage, read> count_counters: array<u32>;
@group(1) @binding(1) var<storage, read_write> vertex_counts: array<u32>;
@group(1) @binding(2) var<storage, read_write> occupied_mask: array<u32>;

var<workgroup> block_vertices: atomic<u32>;

@compute @workgroup_size(64)
fn count_vertices(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                  @builtin(local_invocation_index) lid: u32) {
  let i = grid_workgroup_index(wid, nwg);
  // The whole workgroup takes the same branches (i is uniform), and the
  // barriers stay in uniform control flow.
  let live = i < count_counters[C_ACTIVE_GATED];
  let b = select(0u, active_ids[min(i, arrayLength(&active_ids) - 1u)], live);
  // (workgroup memory starts zeroed: block_vertices is 0)
  if (live) {
    load_block(b, lid);
  }
  workgroupBarrier();
  if (live) {
    let n = cell_vertex_count(load_cell(b, cell_of(lid)).case_index);
    if (n > 0u) {
      atomicAdd(&block_vertices, n);
    }
  }
  workgroupBarrier();
  if (live && lid == 0u) {
    let total = atomicLoad(&block_vertices);
    vertex_counts[i] = total;
    occupied_mask[i] = select(0u, 1u, total > 0u);
  }
}

// ---- Pass 2: the vertices of the occupied blocks reaching one shard.
@compute @workgroup_size(64)
fn emit_vertices(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                 @builtin(local_invocation_index) lid: u32) {
  let w = grid_workgroup_index(wid, nwg);
  let live = w < shard[S_COUNT];
  var entry = 0u;
  if (live) {
    entry = occupied_list[shard[S_FIRST] + w];
  }
  let b = active_ids[entry];
  // (workgroup memory starts zeroed: so do cell_counts)
  if (live) {
    load_block(b, lid);
  }
  workgroupBarrier();
  let l = cell_of(lid);
  var cell: Cell;
  var n = 0u;
  if (live) {
    cell = load_cell(b, l);
    n = cell_vertex_count(cell.case_index);
    if (n > 0u) {
      atomicOr(&cell_counts[lid >> 3u], n << (4u * (lid & 7u)));
    }
  }
  workgroupBarrier();
  if (live && n > 0u) {
    emit_cell(cell, l, b, vertex_offsets[entry] + cells_before(lid));
  }
}
