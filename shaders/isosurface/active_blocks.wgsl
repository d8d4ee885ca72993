// Active blocks. A block is active when the isovalue lies in the hull of its
// value range with the range of some of its 26 neighbours, which is the same
// as lying in [min, max] over its 27-block neighbourhood (if the block is
// entirely below iso and a neighbour reaches it, the pair's hull covers iso,
// and conversely). So `neighbourhood_ranges` runs once at load and each
// isovalue needs one compare per block (`mark_group_blocks` in
// active_groups.wgsl, for the blocks of the active groups only).
// A cell emits triangles only when some corner is >= iso and some is < iso
// (value >= iso is inside), hence the test lo < iso <= hi; every block such
// a cell touches has all the cell's corners in its neighbourhood, so it is
// active too (block_mc_common.wgsl relies on this).

@group(0) @binding(0) var<uniform> volume: VolumeParams;
@group(0) @binding(1) var<storage, read> block_ranges: array<vec2f>;
@group(0) @binding(2) var<storage, read_write> neighbourhood_ranges: array<vec2f>;

@compute @workgroup_size(64)
fn neighbourhood_range(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                       @builtin(local_invocation_index) lid: u32) {
  let b = grid_invocation_index(wid, nwg, lid, 64u);
  if (b >= volume.block_count) {
    return;
  }
  let c = block_coords_of(b, volume.grid);
  let lo = max(c, vec3u(1u)) - 1u;
  let hi = min(c + 1u, volume.grid - 1u);
  var r = block_ranges[b];
  for (var z = lo.z; z <= hi.z; z++) {
    for (var y = lo.y; y <= hi.y; y++) {
      for (var x = lo.x; x <= hi.x; x++) {
        let o = block_ranges[block_index_of(vec3u(x, y, z), volume.grid)];
        r = vec2f(min(r.x, o.x), max(r.y, o.y));
      }
    }
  }
  neighbourhood_ranges[b] = r;
}
