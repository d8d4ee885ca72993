// Per-block [min, max] of the finite decoded values over the voxels inside
// the volume (padding excluded), 2 f32 per block in raster block order. One
// dispatch per shard over the shard's blocks.

@group(1) @binding(0) var<storage, read_write> ranges: array<f32>;

@compute @workgroup_size(64)
fn block_ranges(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                @builtin(local_invocation_index) lid: u32) {
  let b = stream.shard_first_block + grid_invocation_index(wid, nwg, lid, 64u);
  if (b >= stream.shard_end_block) { return; }
  let r = block_value_range_at(b, block_coords(b));
  ranges[2u * b] = r.x;
  ranges[2u * b + 1u] = r.y;
}

// [min, max] of block b's finite decoded values inside the volume (block
// coordinates `coords`: the padding beyond the volume is left out). Converts
// each integer to float bits as it reads it: one 64-entry private array per
// invocation (decode_block_ints), not a second one of float bits.
fn block_value_range_at(b: u32, coords: vec3u) -> vec2f {
  var q: array<i32, 64>;
  let emax = decode_block_ints(b, &q);
  let c = coords * 4u;
  let d = stream.dims;
  let nx = min(4u, d.x - c.x);
  let ny = min(4u, d.y - c.y);
  let nz = min(4u, d.z - c.z);
  // NaN and +-Inf are skipped (a zfp file may decode to them; volumes we
  // compress have none): a block with no finite value gets the empty range
  // [FLT_MAX, -FLT_MAX], which no isovalue falls in and which leaves the
  // neighbourhood ranges and the volume's value range untouched.
  var lo = 0x1.fffffep+127f;
  var hi = -0x1.fffffep+127f;
  for (var z = 0u; z < nz; z++) {
    for (var y = 0u; y < ny; y++) {
      for (var x = 0u; x < nx; x++) {
        let bits = int_to_float_bits(q[16u * z + 4u * y + x], emax);
        if ((bits & 0x7f800000u) == 0x7f800000u) { continue; }
        let f = bitcast<f32>(bits);
        lo = min(lo, f);
        hi = max(hi, f);
      }
    }
  }
  return vec2f(lo, hi);
}
