// Decodes one fixed-rate float32 block into 64 float32 bit patterns, voxel
// (x, y, z) of the block at x + 4y + 16z. Needs stream.wgsl (reader) and
// codec.wgsl. Mirrors zfp 1.0.1's decode_block / decode_ints: bit planes from
// the most significant down, each plane as "first n bits verbatim" then group
// tests, until the block's bit budget is spent.

fn decode_block(b: u32, out: ptr<function, array<u32, 64>>) {
  let start = block_start(b);
  reader_seek(start.x, start.y);
  if (read_bit() == 0u) {
    for (var i = 0u; i < 64u; i++) { (*out)[i] = 0u; }
    return;
  }
  let emax = i32(read_bits(8u)) - 127;
  var bits = stream.bits_per_block - 9u;  // budget for the coefficients
  // *out first holds the negabinary coefficients (sequency order), then the floats
  for (var i = 0u; i < 64u; i++) { (*out)[i] = 0u; }
  var n = 0u;                             // coefficients known to be significant
  var k = 32u;
  loop {
    if (bits == 0u || k == 0u) { break; }
    k -= 1u;
    // first n bits of plane k verbatim
    let m = min(n, bits);
    bits -= m;
    var lo = read_bits(min(m, 32u));
    var hi = read_bits(select(0u, m - 32u, m > 32u));
    // group tests for the rest of the plane
    loop {
      if (n >= 64u || bits == 0u) { break; }
      bits -= 1u;
      if (read_bit() == 0u) { break; }
      loop {
        if (n >= 63u || bits == 0u) { break; }
        bits -= 1u;
        if (read_bit() != 0u) { break; }
        n += 1u;
      }
      if (n < 32u) { lo |= 1u << n; } else { hi |= 1u << (n - 32u); }
      n += 1u;
    }
    // deposit plane k
    let bit = 1u << k;
    loop {
      if (lo == 0u) { break; }
      (*out)[countTrailingZeros(lo)] |= bit;
      lo &= lo - 1u;
    }
    loop {
      if (hi == 0u) { break; }
      (*out)[countTrailingZeros(hi) + 32u] |= bit;
      hi &= hi - 1u;
    }
  }
  var q: array<i32, 64>;
  for (var i = 0u; i < 64u; i++) {
    q[PERM[i]] = bitcast<i32>(((*out)[i] ^ NB) - NB);
  }
  inv_xform(&q);
  for (var i = 0u; i < 64u; i++) {
    (*out)[i] = int_to_float_bits(q[i], emax);
  }
}
