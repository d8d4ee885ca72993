// Hierarchical active-block selection: groups of edge^3 blocks (a stream's:
// in raster order over the group grid; a pool's: its slots, the resident
// chunks, blocks_pool.wgsl), each with the range of its blocks'
// neighbourhood ranges (a stream's computed once at load, a pool's as
// chunks come and go).
// Per isovalue: one compare per group, then one compare per block of the
// active groups only, so the cost follows the surface, not the volume.
// A block is active (lo < iso <= hi over its 27-block neighbourhood,
// active_blocks.wgsl) only if its group's range covers iso, so no active
// block is missed. The active list is group-major: the active groups in
// raster order, the blocks of each in raster order within the group.
// Every kernel has its own bindings in group 1 (no two resource variables of
// this module share a binding).

struct GroupParams {
  grid: vec3u,      // groups per axis
  edge: u32,        // blocks per group along each axis
  count: u32,       // groups
  per_group: u32,   // edge^3
  pad0: u32,
  pad1: u32,
}

@group(0) @binding(0) var<uniform> volume: VolumeParams;
@group(0) @binding(1) var<uniform> groups: GroupParams;

// The id of block `local` (raster order within the group) of group g, NONE when absent (blocks_*.wgsl).
fn group_block(g: u32, local: u32) -> u32 {
  return group_block_id(g, local, volume.grid, groups.grid, groups.edge);
}

// ---- at load: each group's range over its blocks' neighbourhood ranges
@group(1) @binding(0) var<storage, read> load_neighbourhood_ranges: array<vec2f>;
@group(1) @binding(1) var<storage, read_write> load_group_ranges: array<vec2f>;

@compute @workgroup_size(64)
fn group_range(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
               @builtin(local_invocation_index) lid: u32) {
  let g = grid_invocation_index(wid, nwg, lid, 64u);
  if (g >= groups.count) {
    return;
  }
  load_group_ranges[g] = group_range_of(g);
}

fn group_range_of(g: u32) -> vec2f {
  // an empty range (lo > hi) covers no isovalue
  var r = vec2f(3.0e38, -3.0e38);
  for (var local = 0u; local < groups.per_group; local++) {
    let b = group_block(g, local);
    if (b != NONE) {
      let o = load_neighbourhood_ranges[b];
      r = vec2f(min(r.x, o.x), max(r.y, o.y));
    }
  }
  return r;
}

// ---- chunked volumes (groups are the slots): after chunks arrived or left,
// the ranges of their slots and of the resident chunks around them, whose
// blocks' neighbourhood ranges may have changed (entry i: neighbour i % 27
// of chunk changed_chunks[i / 27].y, whose slot is .x; an emptied slot gets
// the empty range).
struct ChangedChunks {
  count: u32,
  pad0: u32,
  pad1: u32,
  pad2: u32,
  chunk_grid: vec3u,  // chunks per axis of the level
  pad3: u32,
}

@group(2) @binding(0) var<storage, read> changed_chunks: array<vec2u>;
@group(2) @binding(1) var<uniform> changed: ChangedChunks;

@compute @workgroup_size(64)
fn group_range_chunks(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                      @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, 64u);
  if (i >= changed.count * 27u) {
    return;
  }
  let entry = changed_chunks[i / 27u];
  let k = i % 27u;
  if (k == 13u) {
    // the slot itself (its chunk now, or none)
    load_group_ranges[entry.x] = group_range_of(entry.x);
    return;
  }
  let gg = changed.chunk_grid;
  let chunk = entry.y;
  let cc = vec3u(chunk % gg.x, (chunk / gg.x) % gg.y, chunk / (gg.x * gg.y));
  let c = vec3i(cc) + vec3i(i32(k % 3u), i32((k / 3u) % 3u), i32(k / 9u)) - vec3i(1);
  if (any(c < vec3i(0)) || any(vec3u(c) >= gg)) {
    return;
  }
  let g = group_of_chunk(u32(c.x) + gg.x * (u32(c.y) + gg.y * u32(c.z)));
  if (g != NONE) {
    load_group_ranges[g] = group_range_of(g);
  }
}

// ---- per isovalue, pass 1: one compare per group
// A pool's idle chunks (ChunkedVolume.setRoles) are never active: their
// blocks cost nothing per isovalue and no cell reads their voxels.
@group(1) @binding(2) var<storage, read> mark_group_ranges: array<vec2f>;
@group(1) @binding(3) var<storage, read_write> group_mask: array<u32>;

@compute @workgroup_size(64)
fn mark_active_groups(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                      @builtin(local_invocation_index) lid: u32) {
  let g = grid_invocation_index(wid, nwg, lid, 64u);
  if (g >= groups.count) {
    return;
  }
  let r = mark_group_ranges[g];
  group_mask[g] = select(0u, 1u, r.x < volume.iso && volume.iso <= r.y && group_role(g) != ROLE_IDLE);
}

// ---- per isovalue, pass 2: one compare per block of the active groups
// (entry i = active group i / per_group, block i % per_group of it); the
// block ids go along for the compaction into the active list.
@group(1) @binding(4) var<storage, read> blocks_counters: array<u32>;
@group(1) @binding(5) var<storage, read> blocks_active_groups: array<u32>;
@group(1) @binding(6) var<storage, read> blocks_neighbourhood_ranges: array<vec2f>;
@group(1) @binding(7) var<storage, read_write> block_mask: array<u32>;
@group(1) @binding(8) var<storage, read_write> block_ids: array<u32>;

@compute @workgroup_size(64)
fn mark_group_blocks(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                     @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, 64u);
  if (i >= blocks_counters[C_GROUP_BLOCKS]) {
    return;
  }
  let b = group_block(blocks_active_groups[i / groups.per_group], i % groups.per_group);
  var is_active = false;
  if (b != NONE) {
    let r = blocks_neighbourhood_ranges[b];
    is_active = r.x < volume.iso && volume.iso <= r.y;
  }
  block_mask[i] = select(0u, 1u, is_active);
  block_ids[i] = select(b, 0u, b == NONE);
}
