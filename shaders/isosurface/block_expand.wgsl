// expand_cells: see block_mc_common.wgsl. Needs common.wgsl, shaders/common/grid.wgsl,
// shaders/mc/case_table.wgsl (its own bindings: no cache buffers).

// ---- expand_cells (its own bind group: no cache bindings)
@group(0) @binding(0) var<uniform> expand_case_table: array<vec4u, 128>;
@group(0) @binding(1) var<storage, read> expand_counters: array<u32>;
@group(0) @binding(2) var<storage, read> expand_cases: array<u32>;
@group(0) @binding(3) var<storage, read> expand_cells_of: array<u32>;      // block_cells
@group(0) @binding(4) var<storage, read> expand_cell_offsets: array<u32>;  // exclusive scan of block_cells
@group(0) @binding(5) var<storage, read> expand_vertex_offsets: array<u32>;
@group(0) @binding(6) var<storage, read_write> expand_cell_records: array<u32>;
@group(0) @binding(7) var<storage, read_write> expand_cell_first: array<u32>;

@compute @workgroup_size(64)
fn expand_cells(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, 64u);
  if (i >= expand_counters[C_ACTIVE_GATED] || expand_cells_of[i] == 0u) {
    return;
  }
  var at = expand_cell_offsets[i];
  var first = expand_vertex_offsets[i];
  for (var w = 0u; w < 16u; w++) {
    let word = expand_cases[16u * i + w];
    if (word == 0u) {
      continue;
    }
    for (var x = 0u; x < 4u; x++) {
      let code = (word >> (8u * x)) & 255u;
      if (code != 0u) {
        let t = expand_case_table[code >> 1u];
        let words = select(t.xy, t.zw, (code & 1u) == 1u);
        // (entry << 6) | cell: entries < 2^26 (the slot data is one binding of 256 B per slot)
        expand_cell_records[at] = (i << 6u) | (4u * w + x);
        expand_cell_first[at] = first;
        at += 1u;
        first += 3u * mc_case_triangles(words);
      }
    }
  }
}

