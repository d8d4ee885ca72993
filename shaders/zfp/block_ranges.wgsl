// Per-block [min, max] of the decoded values over the voxels inside the
// volume (padding excluded), 2 f32 per block in raster block order. One
// dispatch per shard over the shard's blocks.

@group(1) @binding(0) var<storage, read_write> ranges: array<f32>;

@compute @workgroup_size(64)
fn block_ranges(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                @builtin(local_invocation_index) lid: u32) {
  let b = stream.shard_first_block + linear_workgroup_index(wid, nwg) * 64u + lid;
  if (b >= stream.shard_end_block) { return; }
  var v: array<u32, 64>;
  decode_block(b, &v);
  let c = block_coords(b) * 4u;
  let d = stream.dims;
  let nx = min(4u, d.x - c.x);
  let ny = min(4u, d.y - c.y);
  let nz = min(4u, d.z - c.z);
  var lo = bitcast<f32>(v[0]);
  var hi = lo;
  for (var z = 0u; z < nz; z++) {
    for (var y = 0u; y < ny; y++) {
      for (var x = 0u; x < nx; x++) {
        let f = bitcast<f32>(v[16u * z + 4u * y + x]);
        lo = min(lo, f);
        hi = max(hi, f);
      }
    }
  }
  ranges[2u * b] = lo;
  ranges[2u * b + 1u] = hi;
}
