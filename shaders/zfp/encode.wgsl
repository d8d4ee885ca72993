// Fixed-rate zfp encoder, one invocation per block: gathers the block from a
// volume of uint8/int8/uint16/int16/float32/float64 (converted to float32 as
// numpy's astype does), pads partial blocks as zfp does, and writes exactly
// bits_per_block bits at the block's place in the output shard (atomicOr into
// a zeroed buffer: neighbouring blocks share boundary words). Invocation 0 also
// writes the zfp header words when the shard starts the stream.
// Needs u64.wgsl, codec.wgsl, f64.wgsl, source_values.wgsl and shaders/common/grid.wgsl.

struct EncodeParams {
  dims: vec3u,            // nx, ny, nz
  dtype: u32,             // DTYPE (checked on the CPU side; kept for the record)
  blocks: vec3u,          // blocks per axis
  bits_per_block: u32,
  first_block: u32,       // blocks [first_block, end_block) go to this shard
  end_block: u32,
  bit_base: u32,          // bit of first_block in out_words
  input_z: u32,           // first z plane held by input_words
  header_count: u32,      // header words to OR in (0 unless the shard starts the stream)
  header_word: u32,       // where the header goes in out_words (a pool slot's first word; 0 for a stream)
  _pad1: u32,
  _pad2: u32,
  header: array<vec4u, 2>,
}

@group(0) @binding(0) var<storage, read> input_words: array<u32>;
@group(0) @binding(1) var<storage, read_write> out_words: array<atomic<u32>>;
@group(0) @binding(2) var<uniform> eparams: EncodeParams;

// ---- LSB-first bit writer (per invocation).
var<private> wr_word: u32;
var<private> wr_buf: u32;
var<private> wr_pos: u32;  // bits already in wr_buf, < 32

fn write_bits(v: u32, n: u32) {  // n <= 32; v has no bits at or above n
  if (n == 0u) { return; }
  wr_buf |= v << wr_pos;
  let total = wr_pos + n;
  if (total >= 32u) {
    if (wr_buf != 0u) { atomicOr(&out_words[wr_word], wr_buf); }
    wr_word += 1u;
    wr_buf = select(0u, v >> (32u - wr_pos), wr_pos > 0u);
    wr_pos = total - 32u;
  } else {
    wr_pos = total;
  }
}

fn write_bit(b: u32) -> u32 {
  write_bits(b, 1u);
  return b;
}

fn writer_flush() {
  if (wr_pos > 0u && wr_buf != 0u) { atomicOr(&out_words[wr_word], wr_buf); }
}

// In-place transpose of the 32x32 bit matrix p[o..o+32) (row r = word, column
// c = bit c): afterwards bit r of word c is what bit c of word r was.
fn transpose32(p: ptr<function, array<u32, 64>>, o: u32) {
  var m = 0x0000ffffu;
  var j = 16u;
  loop {
    if (j == 0u) { break; }
    var k = 0u;
    loop {
      if (k >= 32u) { break; }
      let a = (*p)[o + k];
      let b = (*p)[o + k + j];
      let t = ((a >> j) ^ b) & m;
      (*p)[o + k] = a ^ (t << j);
      (*p)[o + k + j] = b ^ t;
      k = (k + j + 1u) & ~j;
    }
    j >>= 1u;
    m ^= m << j;
  }
}

@compute @workgroup_size(64)
fn encode_blocks(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                 @builtin(local_invocation_index) lid: u32) {
  let g = grid_invocation_index(wid, nwg, lid, 64u);
  if (g == 0u) {
    for (var h = 0u; h < eparams.header_count; h++) {
      atomicOr(&out_words[eparams.header_word + h], eparams.header[h >> 2u][h & 3u]);
    }
  }
  let b = eparams.first_block + g;
  if (b >= eparams.end_block) { return; }

  // gather (x + 4y + 16z) with zfp's padding
  let bx = eparams.blocks.x;
  let by = eparams.blocks.y;
  let c = vec3u(b % bx, (b / bx) % by, b / (bx * by)) * 4u;
  let d = eparams.dims;
  let nx = min(4u, d.x - c.x);
  let ny = min(4u, d.y - c.y);
  let nz = min(4u, d.z - c.z);
  var f: array<u32, 64>;
  for (var i = 0u; i < 64u; i++) {
    let x = pad_index(i & 3u, nx);
    let y = pad_index((i >> 2u) & 3u, ny);
    let z = pad_index(i >> 4u, nz);
    f[i] = load_value(c.x + x + d.x * (c.y + y + d.y * (c.z + z - eparams.input_z)));
  }

  let start = u64_bit_to_word(u64_add32(u64_mul(b - eparams.first_block, eparams.bits_per_block), eparams.bit_base));
  wr_word = start.x;
  wr_buf = 0u;
  wr_pos = start.y;

  let emax = block_emax(&f);
  let e = u32(emax + 127);
  if (e == 0u) {
    return;  // a single 0 bit, then zero padding: the buffer is already zero
  }
  write_bits(2u * e + 1u, 9u);
  var q: array<i32, 64>;
  for (var i = 0u; i < 64u; i++) { q[i] = float_to_int(f[i], emax); }
  fwd_xform(&q);
  // f is free now: it holds the negabinary coefficients in sequency order
  for (var i = 0u; i < 64u; i++) { f[i] = (bitcast<u32>(q[PERM[i]]) + NB) ^ NB; }

  // bit planes: f[k] = bit k of coefficients 0..31, f[32 + k] = of 32..63
  transpose32(&f, 0u);
  transpose32(&f, 32u);

  var bits = eparams.bits_per_block - 9u;
  var n = 0u;
  var k = 32u;
  loop {
    if (bits == 0u || k == 0u) { break; }
    k -= 1u;
    var lo = f[k];
    var hi = f[32u + k];
    // first n bits verbatim
    let m = min(n, bits);
    bits -= m;
    if (m >= 32u) {
      write_bits(lo, 32u);
      let mh = m - 32u;
      write_bits(hi & select((1u << mh) - 1u, 0xffffffffu, mh == 32u), mh);
      lo = select(hi >> mh, 0u, mh == 32u);
      hi = 0u;
    } else if (m > 0u) {
      write_bits(lo & ((1u << m) - 1u), m);
      lo = (lo >> m) | (hi << (32u - m));
      hi = hi >> m;
    }
    // group tests; (hi, lo) holds the plane's bits from n on
    loop {
      if (bits == 0u || n >= 64u) { break; }
      bits -= 1u;
      if (write_bit(select(0u, 1u, (lo | hi) != 0u)) == 0u) { break; }
      loop {
        if (bits == 0u || n >= 63u) { break; }
        bits -= 1u;
        if (write_bit(lo & 1u) != 0u) { break; }
        lo = (lo >> 1u) | (hi << 31u);
        hi >>= 1u;
        n += 1u;
      }
      lo = (lo >> 1u) | (hi << 31u);
      hi >>= 1u;
      n += 1u;
    }
  }
  writer_flush();
}
