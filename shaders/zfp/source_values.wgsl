// The values a stream is made from: a volume of uint8/int8/uint16/int16/
// float32/float64, read as float32 (as numpy's astype(np.float32) does), and
// zfp's padding of partial blocks. Shared by the encoder and the error meter,
// so both see exactly the same values. The including kernel declares
// `input_words` (the volume's bytes as 32-bit words). Needs f64.wgsl.

// Input type, fixed per pipeline: 0 uint8, 1 int8, 2 uint16, 3 int16, 4 float32, 5 float64.
override DTYPE: u32 = 4u;

// Element i of the input as float32 bits.
fn load_value(i: u32) -> u32 {
  switch (DTYPE) {
    case 0u: {
      return bitcast<u32>(f32((input_words[i >> 2u] >> ((i & 3u) * 8u)) & 0xffu));
    }
    case 1u: {
      let v = bitcast<i32>(input_words[i >> 2u] << (24u - (i & 3u) * 8u)) >> 24u;
      return bitcast<u32>(f32(v));
    }
    case 2u: {
      return bitcast<u32>(f32((input_words[i >> 1u] >> ((i & 1u) * 16u)) & 0xffffu));
    }
    case 3u: {
      let v = bitcast<i32>(input_words[i >> 1u] << (16u - (i & 1u) * 16u)) >> 16u;
      return bitcast<u32>(f32(v));
    }
    case 4u: {
      return input_words[i];
    }
    default: {
      return f64_to_f32_bits(input_words[2u * i], input_words[2u * i + 1u]);
    }
  }
}

// zfp pads a partial block one axis at a time (x, then y, then z), each row
// of n < 4 valid values as: n = 1 -> a a a a, n = 2 -> a b b a, n = 3 -> a b c a.
// Per axis that is a map of positions, so voxel (x, y, z) of the padded block
// is the input voxel (pad_index(x, nx), pad_index(y, ny), pad_index(z, nz)).
fn pad_index(p: u32, n: u32) -> u32 {
  return select(select(0u, 1u, n == 2u && p == 2u), p, p < n);
}
