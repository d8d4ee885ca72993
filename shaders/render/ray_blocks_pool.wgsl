// Block naming for the ray caster (raycast.wgsl) over one level of a
// store: a chunk pool (src/zfp/chunked-volume.ts). A block's id is its
// chunk's pool slot x B + its index in the chunk (B = (C/4)^3, x fastest;
// shaders/isosurface/blocks_pool.wgsl names them the same), found through
// the level's page table; a block whose chunk is not resident has none.
// Which regions the ray traces in this level comes from the step's region
// grid (src/store/view/regions.ts: per cell, the finest level whose leaf
// covers it; a cut made for rays keeps a coarse chunk drawn where only some
// of its finer chunks are, and this is what keeps it out of those): the
// cells this level owns, and two seams:
// - toward a coarser region above one it owns, the first `rays.pool.y`
//   cells of this level into it (from its ghosts): a coarser level's region
//   starts half a coarse voxel further up than a finer one's ends (its
//   voxels' centres are offset), so without that reach a ray would see
//   background in the seam;
// - in a nested cut (for rays: no ghosts, every drawn chunk's coarser
//   ancestors drawn too), below a region it owns, the cells of this level
//   whose lowest corner lies in a finer region within 1.5 of its voxels +
//   1/4 of a level-0 voxel of that region's upper face (finerReachVoxels in
//   src/raycast/seam-reach.ts, passed as level_scale.w, level_offset.w): the finer level has no voxel past its
//   chunk's last, so its rays stop there, and this level's voxels (its drawn
//   chunk over the finer region) fill the seam.
// Where two levels overlap, the depth test keeps the nearer hit. Only chunks
// of the step (drawn or ghost) are read: an idle chunk's slot may hold a
// chunk that arrived since its blocks were cached.

// The level's tables (ChunkedVolume.tables): chunk -> slot, then slot -> chunk | role << 30.
@group(1) @binding(4) var<storage, read> pool_tables: array<u32>;
// The step's region grid: one byte per cell, the level that owns it (255: none), 4 to a word.
@group(1) @binding(5) var<storage, read> region_owner: array<u32>;

const ROLE_DRAWN_CODE: u32 = 0u;
const ROLE_IDLE_CODE: u32 = 2u;

// The pool slot of the chunk at coordinates q, NO_BLOCK when it is outside the level or not resident.
fn chunk_slot(q: vec3i) -> u32 {
  if (any(q < vec3i(0)) || any(vec3u(q) >= rays.chunk_grid.xyz)) {
    return NO_BLOCK;
  }
  let c = vec3u(q);
  return pool_tables[c.x + rays.chunk_grid.x * (c.y + rays.chunk_grid.y * c.z)];
}

// A chunk's role code in the step (drawn 0, ghost 1, idle 2, skirt 3) from its slot.
fn slot_role(slot: u32) -> u32 {
  return pool_tables[rays.chunk_grid.w + slot] >> 30u;
}

fn block_id(b: vec3u) -> u32 {
  let cb = rays.pool.x;
  let slot = chunk_slot(vec3i(b / cb));
  // an idle chunk's cached blocks may be another chunk's (its slot refilled since): a cell reaching into it has no corner there
  if (slot == NO_BLOCK || slot_role(slot) == ROLE_IDLE_CODE) {
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
// finer region overlaps it by the levels' offset. Per axis a region splits
// into the reach above its lower face, the middle, and the reach below its
// upper face (the seams above). Only c's chunk of this level, and only if
// the step has it (drawn or ghost; drawn for the seam below a finer region).
fn region_box(c: vec3u, lo: ptr<function, vec3f>, hi: ptr<function, vec3f>) -> bool {
  let s = rays.level_scale.xyz;
  let off = rays.level_offset.xyz;
  let edge = rays.region_edge.xyz;
  let corner = vec3f(c);
  let p0 = corner * s + off;
  let q = vec3i(floor(p0 / edge));
  let qlo = vec3f(q) * edge;
  let up_end = qlo + min(f32(rays.pool.y) * s, edge);
  let down_start = qlo + edge - min(rays.level_scale.w * s + rays.level_offset.w, edge);
  let near = p0 < up_end;
  let high = p0 >= down_start;
  let blo = max(max(qlo, select(up_end, qlo, near)), select(qlo, down_start, high));
  let bhi = min(min(qlo + edge, select(qlo + edge, up_end, near)), select(down_start, qlo + edge, high));
  // the cells whose lowest corner lies in [blo, bhi), within c's chunk
  let chunk_edge = f32(4u * rays.pool.x);
  let cq = floor(corner / chunk_edge);
  *lo = min(max(ceil((blo - off) / s), cq * chunk_edge), corner);
  *hi = max(min(ceil((bhi - off) / s), (cq + 1.0) * chunk_edge), corner + 1.0);
  let slot = chunk_slot(vec3i(cq));
  if (slot == NO_BLOCK) {
    return false;
  }
  let role = slot_role(slot);
  if (role == ROLE_IDLE_CODE) {
    return false;
  }
  let level = rays.region_grid.w;
  let owner = region_owner_at(q);
  if (owner == level) {
    return true;
  }
  for (var k = 1u; k < 8u; k++) {
    let axes = vec3<bool>((k & 1u) != 0u, (k & 2u) != 0u, (k & 4u) != 0u);
    let step = select(vec3i(0), vec3i(1), axes);
    // above a region of this level, into a coarser one (or none), on every axis c is near the lower face
    if (owner > level && all(!axes | near) && region_owner_at(q - step) == level) {
      return true;
    }
    // below a region of this level, in a finer one over which this level's chunk is drawn (a nested cut)
    if (owner < level && role == ROLE_DRAWN_CODE && all(!axes | high) && region_owner_at(q + step) == level) {
      return true;
    }
  }
  return false;
}
