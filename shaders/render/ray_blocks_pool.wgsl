// Block naming for the ray caster (raycast.wgsl) over one level of a
// store: a chunk pool (src/zfp/chunked-volume.ts). A block's id is its
// chunk's pool slot x B + its index in the chunk (B = (C/4)^3, x fastest;
// shaders/isosurface/blocks_pool.wgsl names them the same), found through
// the level's page table; a block whose chunk is not resident has none.
// Which regions the ray traces in this level comes from the step's region
// grid (src/store/view/regions.ts: per cell, the finest level whose leaf
// covers it; a cut made for rays keeps a coarse chunk drawn where only some
// of its finer chunks are, and this is what keeps it out of those): the
// cells this level owns, and on their upper sides the first
// `rays.pool.y` cells of this level into the next region: a coarser
// level's region starts half a coarse voxel further up than a finer one's
// ends (its voxels' centres are offset), so without that reach a ray would
// see background in the seam. Where the two overlap, the depth test keeps
// the nearer hit. Only chunks of the step (drawn or ghost) are read: an
// idle chunk's slot may hold a chunk that arrived since its blocks were cached.

// The level's tables (ChunkedVolume.tables): chunk -> slot, then slot -> chunk | role << 30.
@group(1) @binding(4) var<storage, read> pool_tables: array<u32>;
// The step's region grid: one byte per cell, the level that owns it (255: none), 4 to a word.
@group(1) @binding(5) var<storage, read> region_owner: array<u32>;

const ROLE_IDLE_CODE: u32 = 2u;

// The pool slot of the chunk at coordinates q, NO_BLOCK when it is outside the level or not resident.
fn chunk_slot(q: vec3i) -> u32 {
  if (any(q < vec3i(0)) || any(vec3u(q) >= rays.chunk_grid.xyz)) {
    return NO_BLOCK;
  }
  let c = vec3u(q);
  return pool_tables[c.x + rays.chunk_grid.x * (c.y + rays.chunk_grid.y * c.z)];
}

fn block_id(b: vec3u) -> u32 {
  let cb = rays.pool.x;
  let slot = chunk_slot(vec3i(b / cb));
  if (slot == NO_BLOCK) {
    return NO_BLOCK;
  }
  let r = b % cb;
  return slot * cb * cb * cb + r.x + cb * (r.y + cb * r.z);
}

// The level owning region cell q (255 outside the grid).
fn region_owner_at(q: vec3i) -> u32 {
  if (any(q < vec3i(0)) || any(vec3u(q) >= rays.region_grid.xyz)) {
    return 255u;
  }
  let i = u32(q.x) + rays.region_grid.x * (u32(q.y) + rays.region_grid.y * u32(q.z));
  return (region_owner[i >> 2u] >> (8u * (i & 3u))) & 0xffu;
}

// Whether cell c (this level's voxels) is this level's to trace, and the
// box of whole cells around it (this level's voxels) where that answer
// holds. A cell goes with the region its lowest corner (a voxel) lies in, as
// a chunk's cells go with the chunk: a coarse level's last cell before a
// finer region overlaps it by the levels' offset, and a level reaches
// `rays.pool.y` cells into the region above its own. Only p's chunk of this
// level, and only if the step has it (drawn or ghost).
fn region_box(c: vec3u, lo: ptr<function, vec3f>, hi: ptr<function, vec3f>) -> bool {
  let s = rays.level_scale.xyz;
  let off = rays.level_offset.xyz;
  let edge = rays.region_edge.xyz;
  let corner = vec3f(c);
  let p0 = corner * s + off;
  let q = vec3i(floor(p0 / edge));
  let qlo = vec3f(q) * edge;
  let reach = min(f32(rays.pool.y) * s, edge);
  let near = p0 - qlo < reach;
  let blo = select(qlo + reach, qlo, near);
  let bhi = select(qlo + edge, qlo + reach, near);
  // the cells whose lowest corner lies in [blo, bhi), within c's chunk
  let chunk_edge = f32(4u * rays.pool.x);
  let cq = floor(corner / chunk_edge);
  *lo = min(max(ceil((blo - off) / s), cq * chunk_edge), corner);
  *hi = max(min(ceil((bhi - off) / s), (cq + 1.0) * chunk_edge), corner + 1.0);
  let slot = chunk_slot(vec3i(cq));
  if (slot == NO_BLOCK || (pool_tables[rays.chunk_grid.w + slot] >> 30u) == ROLE_IDLE_CODE) {
    return false;
  }
  let level = rays.region_grid.w;
  if (region_owner_at(q) == level) {
    return true;
  }
  // the reach of this level's regions just below, on every axis c is near
  for (var k = 1u; k < 8u; k++) {
    let axes = vec3<bool>((k & 1u) != 0u, (k & 2u) != 0u, (k & 4u) != 0u);
    if (all(!axes | near) && region_owner_at(q - select(vec3i(0), vec3i(1), axes)) == level) {
      return true;
    }
  }
  return false;
}
