// Block naming for the ray caster (raycast.wgsl) over one level of a
// store: a chunk pool (src/zfp/chunked-volume.ts). A block's id is its
// chunk's pool slot x B + its index in the chunk (B = (C/4)^3, x fastest;
// shaders/isosurface/blocks_pool.wgsl names them the same), found through
// the level's page table; a block whose chunk is not resident has none.
// The ray enters only the chunks this level draws in the step (role drawn),
// and, on their upper sides, the first `rays.pool.y` cells of the ghost
// chunks above them: a coarser level's region starts half a coarse voxel
// further up than a finer one's ends (its voxels' centres are offset), so
// without that reach a ray would see background in the seam. Where the
// two overlap, the depth test keeps the nearer hit.

// The level's tables (ChunkedVolume.tables): chunk -> slot, then slot -> chunk | role << 30.
@group(1) @binding(4) var<storage, read> pool_tables: array<u32>;

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

fn chunk_drawn(q: vec3i) -> bool {
  let slot = chunk_slot(q);
  return slot != NO_BLOCK && (pool_tables[rays.chunk_grid.w + slot] >> 30u) == ROLE_DRAWN_CODE;
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

// Blocks (per edge) of the aligned region around b the ray skips whole:
// 0 when b is this level's to draw, REGION_PARTIAL when only its cells
// within reach of a drawn chunk below are (cell_outside says which), 1 to
// skip the block alone, the chunk edge to skip its whole chunk (not
// resident, or not drawn and no drawn chunk just below).
fn region_skip(b: vec3u) -> u32 {
  let cb = rays.pool.x;
  let q = vec3i(b / cb);
  let slot = chunk_slot(q);
  if (slot == NO_BLOCK) {
    return cb;
  }
  let role = pool_tables[rays.chunk_grid.w + slot] >> 30u;
  if (role == ROLE_DRAWN_CODE) {
    return 0u;
  }
  // an idle chunk's slot may hold a chunk that arrived since its blocks were cached: only the step's ghosts are read
  let reach = rays.pool.y;
  if (reach == 0u || role == ROLE_IDLE_CODE) {
    return cb;
  }
  var below_drawn = false;
  // the drawn chunks whose upper reach could hold b: b's chunk minus one on any set of axes
  for (var k = 1u; k < 8u; k++) {
    let axes = vec3<bool>((k & 1u) != 0u, (k & 2u) != 0u, (k & 4u) != 0u);
    if (chunk_drawn(q - select(vec3i(0), vec3i(1), axes))) {
      below_drawn = true;
      // within reach (its first cell) on every axis it was lowered on
      if (all(!axes | (4u * (b % cb) < vec3u(reach)))) {
        return REGION_PARTIAL;
      }
    }
  }
  return select(cb, 1u, below_drawn);
}

// Whether the cell at c (in a block region_skip called partial) lies beyond
// the reach of every drawn chunk below it.
fn cell_outside(c: vec3u) -> bool {
  let edge = 4u * rays.pool.x;
  let q = vec3i(c / edge);
  let near = c % edge < vec3u(rays.pool.y);
  for (var k = 1u; k < 8u; k++) {
    let axes = vec3<bool>((k & 1u) != 0u, (k & 2u) != 0u, (k & 4u) != 0u);
    if (all(!axes | near) && chunk_drawn(q - select(vec3i(0), vec3i(1), axes))) {
      return false;
    }
  }
  return true;
}
