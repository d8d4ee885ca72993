// float64 -> float32 conversion on 32-bit words (WGSL has no f64): round to
// nearest, ties to even, with subnormal results, overflow to infinity and
// NaN kept quiet with its top payload bits (as x86's cvtsd2ss and numpy's
// astype(np.float32) do).

fn f64_to_f32_bits(lo: u32, hi: u32) -> u32 {
  let sign = hi & 0x80000000u;
  let e = (hi >> 20u) & 0x7ffu;
  let mhi = hi & 0xfffffu;  // mantissa bits 51..32
  if (e == 0x7ffu) {
    if ((mhi | lo) == 0u) { return sign | 0x7f800000u; }
    return sign | 0x7fc00000u | (mhi << 3u) | (lo >> 29u);
  }
  if (e == 0u) {
    return sign;  // below 2^-1022: zero in float32
  }
  let exp32 = i32(e) - 1023 + 127;
  if (exp32 >= 255) {
    return sign | 0x7f800000u;
  }
  if (exp32 >= 1) {
    // keep 23 of the 52 mantissa bits; a carry may bump the exponent (to infinity too)
    let m = (mhi << 3u) | (lo >> 29u);
    let rem = lo & 0x1fffffffu;
    let up = rem > 0x10000000u || (rem == 0x10000000u && (m & 1u) == 1u);
    return sign | ((u32(exp32) << 23u) + m + select(0u, 1u, up));
  }
  // subnormal float32: (2^52 + mantissa) * 2^(e - 1075) in units of 2^-149 is
  // the 53-bit significand shifted right by r = 926 - e (>= 30)
  let r = u32(926 - i32(e));
  if (r >= 54u) {
    return sign;
  }
  let shi = mhi | 0x100000u;  // significand bits 52..32
  // q = significand >> r (r in [30, 53]), rem/half compared on the low r bits
  var q: u32;
  var above: bool;  // rem > half
  var tie: bool;    // rem == half
  if (r >= 32u) {
    let s = r - 32u;                        // 0..21
    q = shi >> s;
    // rem = (shi & (2^s - 1)) : lo ; half = 2^(r-1)
    let rh = shi & ((1u << s) - 1u);
    if (s == 0u) {
      above = lo > 0x80000000u;
      tie = lo == 0x80000000u;
    } else {
      let hh = 1u << (s - 1u);
      above = rh > hh || (rh == hh && lo != 0u);
      tie = rh == hh && lo == 0u;
    }
  } else {
    // r in [30, 31]
    q = (lo >> r) | (shi << (32u - r));
    let rem = lo & ((1u << r) - 1u);
    let half = 1u << (r - 1u);
    above = rem > half;
    tie = rem == half;
  }
  let up = above || (tie && (q & 1u) == 1u);
  return sign | (q + select(0u, 1u, up));
}
