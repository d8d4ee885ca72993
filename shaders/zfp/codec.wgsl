// zfp's block transform for 3D blocks of 32-bit integers, and the float32 <->
// block-floating-point conversions, bit-exact with zfp 1.0.1 on x86 (C float
// arithmetic emulated with integer operations, so no GPU rounding mode, FMA or
// flush-to-zero can change a bit). CPU twin: src/zfp/cpu/codec.ts.

const NB: u32 = 0xaaaaaaaau;  // negabinary mask

// Coefficient order by sequency: index i + 4j + 16k, sorted by i+j+k, then i^2+j^2+k^2.
const PERM = array<u32, 64>(
  0u, 1u, 4u, 16u, 20u, 17u, 5u, 2u, 8u, 32u, 21u, 6u, 18u, 24u, 9u, 33u,
  36u, 3u, 12u, 48u, 22u, 25u, 37u, 40u, 34u, 10u, 7u, 19u, 28u, 13u, 49u, 52u,
  41u, 38u, 26u, 23u, 29u, 53u, 11u, 35u, 44u, 14u, 50u, 56u, 42u, 27u, 39u, 45u,
  30u, 54u, 57u, 60u, 51u, 15u, 43u, 46u, 58u, 61u, 55u, 31u, 62u, 59u, 47u, 63u);

// Inverse lifting of the 4 values at p[o], p[o + s], p[o + 2s], p[o + 3s].
fn inv_lift(p: ptr<function, array<i32, 64>>, o: u32, s: u32) {
  var x = (*p)[o];
  var y = (*p)[o + s];
  var z = (*p)[o + 2u * s];
  var w = (*p)[o + 3u * s];
  y += w >> 1u; w -= y >> 1u;
  y += w; w <<= 1u; w -= y;
  z += x; x <<= 1u; x -= z;
  y += z; z <<= 1u; z -= y;
  w += x; x <<= 1u; x -= w;
  (*p)[o] = x;
  (*p)[o + s] = y;
  (*p)[o + 2u * s] = z;
  (*p)[o + 3u * s] = w;
}

fn fwd_lift(p: ptr<function, array<i32, 64>>, o: u32, s: u32) {
  var x = (*p)[o];
  var y = (*p)[o + s];
  var z = (*p)[o + 2u * s];
  var w = (*p)[o + 3u * s];
  x += w; x >>= 1u; w -= x;
  z += y; z >>= 1u; y -= z;
  x += z; x >>= 1u; z -= x;
  w += y; w >>= 1u; y -= w;
  w += y >> 1u; y -= w >> 1u;
  (*p)[o] = x;
  (*p)[o + s] = y;
  (*p)[o + 2u * s] = z;
  (*p)[o + 3u * s] = w;
}

// Inverse transform: along z, then y, then x.
fn inv_xform(p: ptr<function, array<i32, 64>>) {
  for (var i = 0u; i < 16u; i++) { inv_lift(p, i, 16u); }
  for (var i = 0u; i < 16u; i++) { inv_lift(p, (i & 3u) + 16u * (i >> 2u), 4u); }
  for (var i = 0u; i < 16u; i++) { inv_lift(p, 4u * i, 1u); }
}

// Forward transform: along x, then y, then z.
fn fwd_xform(p: ptr<function, array<i32, 64>>) {
  for (var i = 0u; i < 16u; i++) { fwd_lift(p, 4u * i, 1u); }
  for (var i = 0u; i < 16u; i++) { fwd_lift(p, (i & 3u) + 16u * (i >> 2u), 4u); }
  for (var i = 0u; i < 16u; i++) { fwd_lift(p, i, 16u); }
}

// Right shift of m by r in [1, 31] rounded to nearest, ties to even.
fn shr_round_even(m: u32, r: u32) -> u32 {
  let q = m >> r;
  let rem = m & ((1u << r) - 1u);
  let half = 1u << (r - 1u);
  return q + select(0u, 1u, rem > half || (rem == half && (q & 1u) == 1u));
}

// Bits of the float32 C computes as ldexpf(1, emax - 30) * (float)v:
// (float)v rounds to 24 bits (nearest even), the product rounds again
// (nearest even; subnormal, zero and infinity included).
fn int_to_float_bits(v: i32, emax: i32) -> u32 {
  let sign = select(0u, 0x80000000u, v < 0);
  if (v == 0 || emax < -119) {
    return sign;  // 0, or the scale factor 2^(emax - 30) is 0 in float32
  }
  let mag = select(bitcast<u32>(v), 0u - bitcast<u32>(v), v < 0);
  let lz = countLeadingZeros(mag);
  let norm = mag << lz;  // leading one at bit 31
  var m = norm >> 8u;    // 24-bit significand, then rounded: [2^23, 2^24]
  let rem = norm & 0xffu;
  m += select(0u, 1u, rem > 0x80u || (rem == 0x80u && (m & 1u) == 1u));
  // value = m * 2^(biased - 150), biased = the float32 exponent field when m < 2^24
  let biased = 128 - i32(lz) + emax;
  if (biased >= 1) {
    // m = 2^24 carries into the exponent; past the largest exponent: infinity
    return sign | min((u32(biased) << 23u) + m - 0x800000u, 0x7f800000u);
  }
  // subnormal: m * 2^(biased - 1) units of 2^-149, i.e. m >> (1 - biased), rounded again
  let r = u32(1 - biased);
  if (r >= 25u) {
    return sign;
  }
  return sign | shr_round_even(m, r);
}

// C's (int32)(ldexpf(1, 30 - emax) * x) on x86 for float32 bits x, where
// emax >= exponent(x): exact truncation; the scale factor overflows to
// infinity for emax < -97 and cvttss2si then gives 0x80000000 (also for NaN).
fn float_to_int(x: u32, emax: i32) -> i32 {
  let e = (x >> 23u) & 0xffu;
  if (emax < -97 || e == 255u) {
    return i32(-2147483647 - 1);
  }
  let mant = x & 0x7fffffu;
  let mag = select(mant | 0x800000u, mant, e == 0u);
  let sh = i32(max(e, 1u)) - 120 - emax;  // value * 2^(30 - emax) = mag * 2^sh
  var v = 0u;
  if (sh >= 0) {
    v = mag << u32(sh);
  } else if (sh > -32) {
    v = mag >> u32(-sh);
  }
  let r = bitcast<i32>(v);
  return select(r, -r, (x & 0x80000000u) != 0u);
}

// zfp's block exponent: frexp exponent of the largest |x| (NaNs ignored, as
// C's `max < f` ignores them), at least -126; -127 when every value is 0.
fn block_emax(p: ptr<function, array<u32, 64>>) -> i32 {
  var amax = 0u;
  for (var i = 0u; i < 64u; i++) {
    let a = (*p)[i] & 0x7fffffffu;
    if (a <= 0x7f800000u) {
      amax = max(amax, a);
    }
  }
  if (amax == 0u) {
    return -127;
  }
  let e = amax >> 23u;
  return select(i32(e) - 126, -126, e == 0u);
}
