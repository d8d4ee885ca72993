// Decodes blocks [range.x, range.y) of the stream (inside this shard) into a
// float32 volume, x fastest; the output holds z planes from range.z on.

struct VolumeParams {
  range: vec4u,  // first block, end block, first z plane of the output, unused
}

@group(1) @binding(0) var<uniform> vparams: VolumeParams;
@group(1) @binding(1) var<storage, read_write> volume_out: array<u32>;

@compute @workgroup_size(64)
fn decode_volume(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                 @builtin(local_invocation_index) lid: u32) {
  let b = vparams.range.x + grid_invocation_index(wid, nwg, lid, 64u);
  if (b >= vparams.range.y) { return; }
  var q: array<i32, 64>;
  let emax = decode_block_ints(b, &q);
  let c = block_coords(b) * 4u;
  let d = stream.dims;
  let nx = min(4u, d.x - c.x);
  let ny = min(4u, d.y - c.y);
  let nz = min(4u, d.z - c.z);
  for (var z = 0u; z < nz; z++) {
    for (var y = 0u; y < ny; y++) {
      let row = c.x + d.x * (c.y + y + d.y * (c.z + z - vparams.range.z));
      for (var x = 0u; x < nx; x++) {
        volume_out[row + x] = int_to_float_bits(q[16u * z + 4u * y + x], emax);
      }
    }
  }
}
