// Where a block starts in one shard of a whole stream: blocks
// [shard_first_block, shard_end_block) lie back to back from shard_bit_base.
// The other address snippet is pool_address.wgsl (chunks in a pool).

fn block_in_shard(b: u32) -> bool {
  return b >= stream.shard_first_block && b < stream.shard_end_block;
}

// (word, bit) where block b (inside this shard) starts.
fn block_start(b: u32) -> vec2u {
  let bit = u64_add32(u64_mul(b - stream.shard_first_block, stream.bits_per_block), stream.shard_bit_base);
  return u64_bit_to_word(bit);
}
