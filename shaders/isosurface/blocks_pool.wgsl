// Block ids of a chunk pool (ChunkedVolume): a chunk in pool slot s has the
// ids s * B ... s * B + B - 1 (B = (C/4)^3 blocks, raster order within the
// chunk), so everything the pipeline keeps per block is sized by the pool's
// slots, never by the level: a level of any size has ids for what is
// resident only. The page table (chunk -> slot) finds the block at given
// coordinates, the slot table (slot -> chunk) the coordinates of an id. The
// groups of the active-block selection are the slots (the resident chunks).
// A slot-table word also holds its chunk's role (ChunkedVolume.setRoles) in
// its top 2 bits, chunk | role << 30 (ROLE_* in common.wgsl); an empty slot
// is NONE. Every reader of the slot table goes through pool_slot_chunk
// (masks the role off) or pool_slot_role.
// Needs common.wgsl. Bind group 3 of every kernel that composes it.

struct PoolBlocks {
  chunk_grid: vec3u,    // chunks per axis
  chunk_blocks: u32,    // blocks per chunk edge (C / 4)
  slot_table: u32,      // where the slot table starts in pool_tables (the level's chunk count)
  pad0: u32,
  pad1: u32,
  pad2: u32,
}

@group(3) @binding(0) var<uniform> pool_blocks: PoolBlocks;
// The level's tables (ChunkedVolume.tables): the page table (chunk -> slot),
// then the slot table (slot -> chunk | role << 30). One binding: the kernels
// that use it stay within WebGPU's default of 8 storage buffers per stage.
@group(3) @binding(1) var<storage, read> pool_tables: array<u32>;

const POOL_CHUNK_MASK: u32 = 0x3fffffffu;

// The chunk in `slot`, NONE when the slot is empty.
fn pool_slot_chunk(slot: u32) -> u32 {
  let word = pool_tables[pool_blocks.slot_table + slot];
  return select(word & POOL_CHUNK_MASK, NONE, word == NONE);
}

// The role (ROLE_*) of the chunk in `slot` (3 when the slot is empty: ask
// for occupied slots only, or where 3 and not ROLE_IDLE mean the same).
fn pool_slot_role(slot: u32) -> u32 {
  return pool_tables[pool_blocks.slot_table + slot] >> 30u;
}

// The role of block b's chunk (blocks_stream.wgsl: always ROLE_DRAWN).
fn block_role(b: u32) -> u32 {
  let cb = pool_blocks.chunk_blocks;
  return pool_slot_role(b / (cb * cb * cb));
}

// The role of group g's chunk (the group is its slot).
fn group_role(g: u32) -> u32 {
  return pool_slot_role(g);
}

// The axes on which block coordinates c are their chunk's first: the block's
// cells of local coordinate 0 on such an axis lie on the chunk's lower face.
fn block_first_in_chunk(c: vec3u) -> vec3<bool> {
  return c % pool_blocks.chunk_blocks == vec3u(0u);
}

// Whether the chunk below chunk coordinates cc on `axis` is resident and drawn.
fn pool_drawn_below(cc: vec3u, axis: u32) -> bool {
  let g = pool_blocks.chunk_grid;
  var n = cc;
  n[axis] -= 1u;
  let slot = pool_tables[n.x + g.x * (n.y + g.y * n.z)];
  return slot != NONE && pool_slot_role(slot) == ROLE_DRAWN;
}

// The axes a on which block c (of a skirt chunk G, ROLE_SKIRT) is its
// chunk's first and G - e_a is resident and drawn: the block's cells of
// chunk-local coordinate 0 on a make triangles (block_mc_common.wgsl).
// Once per block: a few page-table words.
fn skirt_axes(c: vec3u) -> vec3<bool> {
  let cc = c / pool_blocks.chunk_blocks;
  let first = block_first_in_chunk(c) & (cc > vec3u(0u));
  return vec3<bool>(first.x && pool_drawn_below(cc, 0u), first.y && pool_drawn_below(cc, 1u), first.z && pool_drawn_below(cc, 2u));
}

// Block coordinates of id b (its slot holds a chunk).
fn block_coords(b: u32, grid: vec3u) -> vec3u {
  let cb = pool_blocks.chunk_blocks;
  let per = cb * cb * cb;
  let chunk = pool_slot_chunk(b / per);
  let l = b % per;
  let g = pool_blocks.chunk_grid;
  let cc = vec3u(chunk % g.x, (chunk / g.x) % g.y, chunk / (g.x * g.y));
  return cc * cb + vec3u(l % cb, (l / cb) % cb, l / (cb * cb));
}

// The id of the block at coordinates c (inside the grid), NONE when its chunk is not resident.
fn block_at(c: vec3u, grid: vec3u) -> u32 {
  let cb = pool_blocks.chunk_blocks;
  let g = pool_blocks.chunk_grid;
  let cc = c / cb;
  let slot = pool_tables[cc.x + g.x * (cc.y + g.y * cc.z)];
  if (slot == NONE) {
    return NONE;
  }
  let l = c % cb;
  return slot * cb * cb * cb + l.x + cb * (l.y + cb * l.z);
}

// Bits d (d = dx + 2dy + 4dz, d in {0, 1}^3) of the blocks c + d inside the
// grid whose chunk is not resident or idle: no voxel of theirs is part of
// this surface (block_mc_common.wgsl). Block c itself is active, so
// available; only a block on its chunk's upper faces has neighbours in
// other chunks.
fn unavailable_blocks(c: vec3u, grid: vec3u) -> u32 {
  let cb = pool_blocks.chunk_blocks;
  if (all(c % cb != vec3u(cb - 1u))) {
    return 0u;
  }
  var bits = 0u;
  for (var d = 1u; d < 8u; d++) {
    let n = c + vec3u(d & 1u, (d >> 1u) & 1u, d >> 2u);
    if (all(n < grid)) {
      let b = block_at(n, grid);
      if (b == NONE || block_role(b) == ROLE_IDLE) {
        bits |= 1u << d;
      }
    }
  }
  return bits;
}

// Block `local` of group g (group = pool slot), NONE when the slot is empty or the block outside the volume.
fn group_block_id(g: u32, local: u32, grid: vec3u, group_grid: vec3u, edge: u32) -> u32 {
  if (pool_slot_chunk(g) == NONE) {
    return NONE;
  }
  let b = g * edge * edge * edge + local;
  if (any(block_coords(b, grid) >= grid)) {
    return NONE;
  }
  return b;
}

// The group of chunk `chunk`: its slot, NONE when it is not resident.
fn group_of_chunk(chunk: u32) -> u32 {
  return pool_tables[chunk];
}
