// Decodes one fixed-rate float32 block into 64 float32 bit patterns, voxel
// (x, y, z) of the block at x + 4y + 16z. Needs stream.wgsl (reader) and
// codec.wgsl. Mirrors zfp 1.0.1's decode_block / decode_ints: bit planes from
// the most significant down, each plane as "first n bits verbatim" then group
// tests, until the block's bit budget is spent.

// One 64-entry array per invocation (GPUs keep it in registers or spill it to
// local memory, so fewer is better): the plane bits are deposited straight
// into their transform positions (PERM), the negabinary conversion and the
// inverse transform run in place, and the caller converts each integer to
// float bits as it stores it.
// Returns emax; voxel i's float32 bits are int_to_float_bits(q[i], emax)
// (0 for an empty block, whose q is all 0).
fn decode_block_ints(b: u32, q: ptr<function, array<i32, 64>>) -> i32 {
  for (var i = 0u; i < 64u; i++) { (*q)[i] = 0; }
  let start = block_start(b);
  reader_seek(start.x, start.y);
  if (read_bit() == 0u) {
    return 0;
  }
  let emax = i32(read_bits(8u)) - 127;
  var bits = stream.bits_per_block - 9u;  // budget for the coefficients
  // *q first holds the negabinary coefficients (at their PERM positions), then the integers
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
    let bit = bitcast<i32>(1u << k);
    loop {
      if (lo == 0u) { break; }
      let p = PERM[countTrailingZeros(lo)];
      (*q)[p] |= bit;
      lo &= lo - 1u;
    }
    loop {
      if (hi == 0u) { break; }
      let p = PERM[countTrailingZeros(hi) + 32u];
      (*q)[p] |= bit;
      hi &= hi - 1u;
    }
  }
  for (var i = 0u; i < 64u; i++) {
    (*q)[i] = bitcast<i32>((bitcast<u32>((*q)[i]) ^ NB) - NB);
  }
  inv_xform(q);
  return emax;
}
