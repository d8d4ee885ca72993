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
  neighbourhood_ranges[b] = neighbourhood_of(b);
}

// Over the neighbours present (a pool's: those whose chunk is resident; the
// plan makes every chunk a surface needs resident with its 26 neighbours).
fn neighbourhood_of(b: u32) -> vec2f {
  let c = block_coords(b, volume.grid);
  let lo = max(c, vec3u(1u)) - 1u;
  let hi = min(c + 1u, volume.grid - 1u);
  var r = block_ranges[b];
  for (var z = lo.z; z <= hi.z; z++) {
    for (var y = lo.y; y <= hi.y; y++) {
      for (var x = lo.x; x <= hi.x; x++) {
        let n = block_at(vec3u(x, y, z), volume.grid);
        if (n != NONE) {
          let o = block_ranges[n];
          r = vec2f(min(r.x, o.x), max(r.y, o.y));
        }
      }
    }
  }
  return r;
}

// ---- chunked volumes: after chunks arrived in (or left) the pool, the
// neighbourhood ranges of every resident block within one block of those
// chunks (entry i: block i % (C/4 + 2)^3 of the box of chunk
// region_chunks[i / (C/4 + 2)^3].y grown by one block; .x is its slot).
struct ChunkRegion {
  count: u32,         // chunks in region_chunks
  chunk_blocks: u32,  // blocks per chunk edge
  pad0: u32,
  pad1: u32,
  chunk_grid: vec3u,  // chunks per axis
  pad2: u32,
}

@group(1) @binding(0) var<storage, read> region_chunks: array<vec2u>;
@group(1) @binding(1) var<uniform> region: ChunkRegion;

@compute @workgroup_size(64)
fn neighbourhood_range_chunks(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                              @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, 64u);
  let e = region.chunk_blocks + 2u;
  let per = e * e * e;
  if (i >= region.count * per) {
    return;
  }
  let chunk = region_chunks[i / per].y;
  let l = i % per;
  let g = region.chunk_grid;
  let cc = vec3u(chunk % g.x, (chunk / g.x) % g.y, chunk / (g.x * g.y));
  let c = vec3i(cc * region.chunk_blocks) - vec3i(1) + vec3i(vec3u(l % e, (l / e) % e, l / (e * e)));
  if (any(c < vec3i(0)) || any(vec3u(c) >= volume.grid)) {
    return;
  }
  let b = block_at(vec3u(c), volume.grid);
  if (b == NONE) {
    return;
  }
  neighbourhood_ranges[b] = neighbourhood_of(b);
}
