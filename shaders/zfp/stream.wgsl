// One shard of a fixed-rate zfp stream (bind group 0 of every decoder
// kernel): the 32-bit words holding blocks [shard_first_block,
// shard_end_block), and where they are. Block b starts at bit
// (b - shard_first_block) * bits_per_block + shard_bit_base of `stream_words`
// (block_start in stream_blocks.wgsl; a chunk pool composes its own).
// Needs u64.wgsl.

struct StreamParams {
  dims: vec3u,            // nx, ny, nz of the field
  bits_per_block: u32,
  blocks: vec3u,          // ceil(n / 4) per axis
  block_count: u32,
  shard_first_block: u32,
  shard_end_block: u32,
  shard_bit_base: u32,
  _pad: u32,
}

@group(0) @binding(0) var<storage, read> stream_words: array<u32>;
@group(0) @binding(1) var<uniform> stream: StreamParams;

// ---- LSB-first bit reader over stream_words (per invocation).
var<private> rd_next: u32;   // index of the next word to load
var<private> rd_buf: u32;    // unread bits, LSB first; bits above rd_avail are zero
var<private> rd_avail: u32;  // valid bits in rd_buf

fn reader_seek(word: u32, bit: u32) {
  rd_buf = stream_words[word] >> bit;
  rd_avail = 32u - bit;
  rd_next = word + 1u;
}

fn read_bit() -> u32 {
  if (rd_avail == 0u) {
    rd_buf = stream_words[rd_next];
    rd_next += 1u;
    rd_avail = 32u;
  }
  let b = rd_buf & 1u;
  rd_buf >>= 1u;
  rd_avail -= 1u;
  return b;
}

// n in [0, 32] bits as an integer (first bit in bit 0).
fn read_bits(n: u32) -> u32 {
  if (n == 0u) {
    return 0u;
  }
  let mask = select((1u << n) - 1u, 0xffffffffu, n == 32u);
  if (n <= rd_avail) {
    let v = rd_buf & mask;
    rd_buf = select(rd_buf >> n, 0u, n == 32u);
    rd_avail -= n;
    return v;
  }
  // rd_avail < n <= 32: the rest comes from the next word.
  let w = stream_words[rd_next];
  rd_next += 1u;
  let got = rd_avail;
  let v = select(rd_buf | (w << got), w, got == 0u) & mask;
  let used = n - got;  // 1..32 bits of w
  rd_buf = select(w >> used, 0u, used == 32u);
  rd_avail = 32u - used;
  return v;
}
