// After chunk_block_ranges: the neighbourhood ranges (27 blocks, as
// shaders/isosurface/active_blocks.wgsl) of every block of the dilated list
// (the changed chunks and their 26 neighbours: list[changed .. changed +
// dilated)), then each such chunk's group range (the chunks are the groups of
// the hierarchical selection, active_groups.wgsl). A block of a non-resident
// chunk gets the empty range: it is never active, so it is never decoded.
// Needs chunk_params.wgsl and the grid snippet.

@group(1) @binding(0) var<storage, read> update_list: array<u32>;
@group(1) @binding(1) var<storage, read> nb_block_ranges: array<vec2f>;
@group(1) @binding(2) var<storage, read_write> nb_neighbourhood_ranges: array<vec2f>;

const EMPTY_RANGE = vec2f(0x1.fffffep+127f, -0x1.fffffep+127f);

@compute @workgroup_size(64)
fn chunk_neighbourhood(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                       @builtin(local_invocation_index) lid: u32) {
  let i = linear_workgroup_index(wid, nwg) * 64u + lid;
  if (i >= chunks.dilated * chunks.blocks_per_chunk) { return; }
  let chunk = update_list[chunks.changed + i / chunks.blocks_per_chunk];
  let c = chunk_block(chunk, i % chunks.blocks_per_chunk);
  if (any(c >= chunks.blocks)) { return; }
  var r = EMPTY_RANGE;
  if (page_table[chunk] != NO_SLOT) {
    let lo = max(c, vec3u(1u)) - 1u;
    let hi = min(c + 1u, chunks.blocks - 1u);
    for (var z = lo.z; z <= hi.z; z++) {
      for (var y = lo.y; y <= hi.y; y++) {
        for (var x = lo.x; x <= hi.x; x++) {
          let o = nb_block_ranges[block_index(vec3u(x, y, z))];
          r = vec2f(min(r.x, o.x), max(r.y, o.y));
        }
      }
    }
  }
  nb_neighbourhood_ranges[block_index(c)] = r;
}

@group(1) @binding(3) var<storage, read> gr_neighbourhood_ranges: array<vec2f>;
@group(1) @binding(4) var<storage, read_write> gr_group_ranges: array<vec2f>;

@compute @workgroup_size(64)
fn chunk_group_range(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                     @builtin(local_invocation_index) lid: u32) {
  let i = linear_workgroup_index(wid, nwg) * 64u + lid;
  if (i >= chunks.dilated) { return; }
  let chunk = update_list[chunks.changed + i];
  var r = EMPTY_RANGE;
  for (var local = 0u; local < chunks.blocks_per_chunk; local++) {
    let c = chunk_block(chunk, local);
    if (all(c < chunks.blocks)) {
      let o = gr_neighbourhood_ranges[block_index(c)];
      r = vec2f(min(r.x, o.x), max(r.y, o.y));
    }
  }
  gr_group_ranges[chunk] = r;
}
