// 64-bit unsigned helpers on vec2u (x = low word, y = high word): WGSL has no
// u64, and zfp bit offsets pass 2^32 for streams over 512 MiB.

// a * b as a full 64-bit product.
fn u64_mul(a: u32, b: u32) -> vec2u {
  let a0 = a & 0xffffu;
  let a1 = a >> 16u;
  let b0 = b & 0xffffu;
  let b1 = b >> 16u;
  let p00 = a0 * b0;
  let p01 = a0 * b1;
  let p10 = a1 * b0;
  let p11 = a1 * b1;
  let mid = (p00 >> 16u) + (p01 & 0xffffu) + (p10 & 0xffffu);
  return vec2u((p00 & 0xffffu) | (mid << 16u), p11 + (p01 >> 16u) + (p10 >> 16u) + (mid >> 16u));
}

fn u64_add32(a: vec2u, b: u32) -> vec2u {
  let lo = a.x + b;
  return vec2u(lo, a.y + select(0u, 1u, lo < b));
}

// Bit offset -> (32-bit word index, bit within the word); the word index must fit in 32 bits.
fn u64_bit_to_word(bit: vec2u) -> vec2u {
  return vec2u((bit.x >> 5u) | (bit.y << 27u), bit.x & 31u);
}
