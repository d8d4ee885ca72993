// Where a block starts when the volume arrives as chunks (a chunked store,
// src/zfp/chunked-volume.ts): every chunk of C^3 voxels is a zfp stream of
// its own (header, then its B = (C/4)^3 blocks in raster order), copied
// whole into a slot of a pool. Blocks are named by their pool id: slot * B
// + the block's index within its chunk (shaders/isosurface/blocks_pool.wgsl),
// so finding a block needs no table. The level's tables (one buffer: the
// page table, chunk -> slot, 0xffffffff when not resident, then from word
// slot_table the slot table, slot -> chunk with the chunk's role in the top
// 2 bits, 0xffffffff when empty: slot_table_chunk) serve the passes that
// start from chunks or need coordinates. A pool shard holds
// slots [first_slot, end_slot) back to back, slot_words 32-bit words each.
// The stream uniform still gives the level's dims, block grid and bits per
// block; a chunk's blocks are those of the whole level compressed as one
// stream (zfp codes each block alone).

struct PoolParams {
  chunk_grid: vec3u,    // chunks per axis
  chunk_blocks: u32,    // blocks per chunk edge (C / 4)
  slot_words: u32,      // words per pooled chunk (its stream padded to 64 bits)
  header_bits: u32,     // where block 0 starts inside a chunk's stream
  first_slot: u32,      // slots of this shard
  end_slot: u32,
  slot_table: u32,      // where the slot table starts in `tables` (the level's chunk count)
  _pad0: u32,
  _pad1: u32,
  _pad2: u32,
}

@group(0) @binding(2) var<storage, read> tables: array<u32>;
@group(0) @binding(3) var<uniform> pool: PoolParams;

const POOL_NONE = 0xffffffffu;

// The chunk in `slot` (the slot-table word without its role bits,
// ChunkedVolume.setRoles), POOL_NONE when the slot is empty.
fn slot_table_chunk(slot: u32) -> u32 {
  let word = tables[pool.slot_table + slot];
  return select(word & 0x3fffffffu, POOL_NONE, word == POOL_NONE);
}

fn blocks_per_chunk() -> u32 {
  return pool.chunk_blocks * pool.chunk_blocks * pool.chunk_blocks;
}

fn block_in_shard(b: u32) -> bool {
  let slot = b / blocks_per_chunk();
  return slot >= pool.first_slot && slot < pool.end_slot;
}

// (word, bit) where block b starts; only for blocks in this shard.
fn block_start(b: u32) -> vec2u {
  let per = blocks_per_chunk();
  // < 2^32: ChunkedVolume.create checks that a chunk's stream holds fewer bits
  let bit = pool.header_bits + (b % per) * stream.bits_per_block;
  return vec2u((b / per - pool.first_slot) * pool.slot_words + bit / 32u, bit % 32u);
}
