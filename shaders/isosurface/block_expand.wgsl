// expand_cells: see block_mc_common.wgsl. Needs common.wgsl, shaders/common/grid.wgsl,
// shaders/mc/case_table.wgsl, edge_owner.wgsl (its own bindings: no slot data).

// ---- expand_cells (its own bind group)
@group(0) @binding(0) var<uniform> expand_case_table: array<vec4u, 128>;
@group(0) @binding(1) var<uniform> expand_counters: array<vec4u, 16>;
@group(0) @binding(2) var<storage, read_write> expand_slot_mc: array<u32>;   // cases in, row bases out (block_classify.wgsl)
@group(0) @binding(3) var<storage, read> expand_cells_of: array<u32>;        // emitting cells per active entry (block_classify.wgsl)
// Exclusive scans of the three counts (block_classify.wgsl), one region each
// of count_stride words: triangle corners, welded vertices, emitting cells.
@group(0) @binding(4) var<storage, read> expand_offsets: array<u32>;
@group(0) @binding(5) var<storage, read_write> expand_cell_list: array<vec2u>;
@group(0) @binding(6) var<storage, read> expand_active_ids: array<u32>;
@group(0) @binding(7) var<storage, read> expand_block_to_slot: array<u32>;
@group(0) @binding(8) var<uniform> expand_volume: VolumeParams;

@compute @workgroup_size(64)
fn expand_cells(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, 64u);
  if (i >= expand_counters[C_ACTIVE_GATED >> 2u][C_ACTIVE_GATED & 3u] || expand_cells_of[i] == 0u) {
    return;
  }
  let b = expand_active_ids[i];
  let slot = expand_block_to_slot[b];
  let c = block_coords(b, expand_volume.grid);
  let origin = c * 4u;
  // Cells without indices, as classify_blocks found them (a ghost chunk's,
  // a skirt chunk's but its layer next to a drawn chunk; those next to an
  // unavailable chunk): listed with CELL_NO_INDICES, as they write the
  // vertices they own, adding no index.
  let role = block_role(b);
  // (a branch, not select: select evaluates both, and most blocks are not a skirt's)
  var skirt = vec3<bool>(false);
  if (role == ROLE_SKIRT) {
    skirt = skirt_axes(c);
  }
  let unavailable = unavailable_blocks(c, expand_volume.grid);
  let stride = count_stride(expand_counters[C_SLOTS >> 2u][C_SLOTS & 3u]);
  var first = expand_offsets[i];
  var vertex = expand_offsets[stride + i];
  var at = expand_offsets[2u * stride + i];
  for (var w = 0u; w < 16u; w++) {
    let word = expand_slot_mc[32u * slot + 2u * w];
    // the first vertex the cells of row w own (the emit pass numbers from here)
    expand_slot_mc[32u * slot + 2u * w + 1u] = vertex;
    if (word == 0u) {
      continue;
    }
    vertex += owned_vertices_of_row(word, origin + vec3u(0u, w & 3u, w >> 2u), expand_volume.dims);
    let without = row_without_indices(role, skirt, unavailable, w & 3u, w >> 2u);
    for (var x = 0u; x < 4u; x++) {
      let code = (word >> (8u * x)) & 255u;
      if (code != 0u) {
        let t = expand_case_table[code >> 1u];
        let words = select(t.xy, t.zw, (code & 1u) == 1u);
        let no_indices = ((without >> (8u * x)) & 1u) != 0u;
        // (entry << 6) | cell, and the flag in bit 31: entries < 2^25 slots
        // (maxCacheSlots, budget.ts)
        expand_cell_list[at] = vec2u((i << 6u) | (4u * w + x) | select(0u, CELL_NO_INDICES, no_indices), first);
        at += 1u;
        first += select(3u * mc_case_triangles(words), 0u, no_indices);
      }
    }
  }
}
