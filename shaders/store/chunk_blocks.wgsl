// Block addressing of the decode core (shaders/zfp/decode_block.wgsl) for a
// pool of chunks, in place of shaders/zfp/stream_blocks.wgsl: block b (raster
// order over the level) -> its chunk -> the chunk's pool slot -> the block's
// raster index inside the chunk. Its bits start at
//   slot * chunk_words * 32 + header_bits + local * bits_per_block
// (stream_words = the pool). Only blocks of resident chunks are decoded
// (non-resident chunks have no active blocks); NO_SLOT reads word 0.
// Needs u64.wgsl, stream.wgsl, chunk_params.wgsl.

fn block_coords(b: u32) -> vec3u {
  let bx = stream.blocks.x;
  let by = stream.blocks.y;
  return vec3u(b % bx, (b / bx) % by, b / (bx * by));
}

fn block_start(b: u32) -> vec2u {
  let c = block_coords(b);
  let slot = page_table[chunk_of_block(c)];
  if (slot == NO_SLOT) {
    return vec2u(0u, 0u);
  }
  let e = chunks.edge_blocks;
  let l = c % e;
  let local = l.x + e * (l.y + e * l.z);
  // Inside one chunk the offset fits 32 bits (a chunk is < 4 GiB); the slot's
  // word offset fits too (the pool is one binding).
  let w = u64_bit_to_word(u64_add32(u64_mul(local, stream.bits_per_block), chunks.header_bits));
  return vec2u(slot * chunks.chunk_words + w.x, w.y);
}
