// Where a block of one contiguous stream shard starts, and its coordinates.
// The block addressing of stream.wgsl's reader; a pool of chunks composes
// its own block_start instead (shaders/store/chunk_blocks.wgsl).

// (word, bit) where block b (inside this shard) starts.
fn block_start(b: u32) -> vec2u {
  let bit = u64_add32(u64_mul(b - stream.shard_first_block, stream.bits_per_block), stream.shard_bit_base);
  return u64_bit_to_word(bit);
}

// Block coordinates of raster block index b (x fastest).
fn block_coords(b: u32) -> vec3u {
  let bx = stream.blocks.x;
  let by = stream.blocks.y;
  return vec3u(b % bx, (b / bx) % by, b / (bx * by));
}
