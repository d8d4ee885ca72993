// Block marching cubes with direct reads: each invocation reads its cell's
// 8 corners from the cache itself (the neighbour blocks' slots looked up per
// corner), and the block's vertex count is summed with a storage atomic, so
// the count pass uses no workgroup memory and no barrier; the vertex pass
// keeps the workgroup scan of the per-cell counts (8 words, one barrier).
// On SwiftShader (CPU) this measured several times faster than staging the
// 5^3 neighbourhood in workgroup memory (src/isosurface/README.md).
// Needs block_mc_common.wgsl.

// Cell `l` of block b (cached in own_slot), read from the cache.
fn read_cell(b: u32, own_slot: u32, l: vec3u) -> Cell {
  var cell: Cell;
  cell.case_index = 0u;
  let c = block_coords_of(b, volume.grid);
  if (!cell_inside_volume(c, l)) {
    return cell;
  }
  for (var q = 0u; q < 8u; q++) {
    let p = l + mc_corner_offset(q);
    let d = p >> vec3u(2u);
    var slot = own_slot;
    if (any(d != vec3u(0u))) {
      // inside the grid: the cell is inside the volume
      slot = block_to_slot[block_index_of(c + d, volume.grid)];
      if (slot == NONE) {
        return cell;
      }
    }
    let v = p & vec3u(3u);
    cell.values[q] = slot_data[slot * 64u + v.x + 4u * v.y + 16u * v.z];
  }
  cell.case_index = case_of(cell.values);
  return cell;
}

// ---- Pass 1: vertices per active block, summed with atomics into counts
// cleared before the pass; occupancy is derived in a second small pass.
@group(1) @binding(0) var<storage, read> count_counters: array<u32>;
@group(1) @binding(1) var<storage, read_write> vertex_counts: array<atomic<u32>>;

@compute @workgroup_size(64)
fn count_vertices_direct(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                         @builtin(local_invocation_index) lid: u32) {
  let i = grid_workgroup_index(wid, nwg);
  if (i >= count_counters[C_ACTIVE_GATED]) {
    return;
  }
  let b = active_ids[i];
  let n = cell_vertex_count(read_cell(b, block_to_slot[b], cell_of(lid)).case_index);
  if (n > 0u) {
    atomicAdd(&vertex_counts[i], n);
  }
}

@group(1) @binding(0) var<storage, read> occupancy_counters: array<u32>;
@group(1) @binding(1) var<storage, read> block_counts: array<u32>;
@group(1) @binding(2) var<storage, read_write> block_occupied: array<u32>;

@compute @workgroup_size(64)
fn occupied_from_counts(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                        @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, 64u);
  if (i < occupancy_counters[C_ACTIVE_GATED]) {
    block_occupied[i] = select(0u, 1u, block_counts[i] > 0u);
  }
}

// ---- Pass 2: the vertices of the occupied blocks reaching one shard.
@compute @workgroup_size(64)
fn emit_vertices_direct(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                        @builtin(local_invocation_index) lid: u32) {
  let w = grid_workgroup_index(wid, nwg);
  let live = w < shard[S_COUNT];
  var entry = 0u;
  if (live) {
    entry = occupied_list[shard[S_FIRST] + w];
  }
  let b = active_ids[entry];
  let l = cell_of(lid);
  var cell: Cell;
  var n = 0u;
  if (live) {
    cell = read_cell(b, block_to_slot[b], l);
    n = cell_vertex_count(cell.case_index);
  }
  // (workgroup memory starts zeroed: so do cell_counts)
  if (n > 0u) {
    atomicOr(&cell_counts[lid >> 3u], n << (4u * (lid & 7u)));
  }
  workgroupBarrier();
  if (live && n > 0u) {
    emit_cell(cell, l, b, vertex_offsets[entry] + cells_before(lid));
  }
}
