// How far a fixed-rate stream's decoded values are from the values it was
// made from (what zfpy's decode minus the source gives): one invocation per
// block of one shard decodes the block and compares its voxels inside the
// volume (not zfp's padding) with the source. Each workgroup writes the sum
// of its squared errors (the host adds them in double precision), and the
// largest error goes to one atomic max (non-negative float bits order as
// integers). Needs grid.wgsl, u64.wgsl, stream.wgsl, stream_address.wgsl,
// codec.wgsl, decode_block.wgsl, f64.wgsl and source_values.wgsl.

struct ErrorParams {
  input_z: u32,       // first z plane held by input_words
  sum_base: u32,      // where this shard's workgroup sums start in error_sums
  _pad0: u32,
  _pad1: u32,
}

@group(1) @binding(0) var<storage, read> input_words: array<u32>;
@group(1) @binding(1) var<storage, read_write> error_max: array<atomic<u32>>;
@group(1) @binding(2) var<storage, read_write> error_sums: array<f32>;
@group(1) @binding(3) var<uniform> errparams: ErrorParams;

var<workgroup> wg_sums: array<f32, 64>;

@compute @workgroup_size(64)
fn stream_error(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                @builtin(local_invocation_index) lid: u32) {
  let b = stream.shard_first_block + grid_invocation_index(wid, nwg, lid, 64u);
  var sum = 0.0;
  var largest = 0.0;
  if (b < stream.shard_end_block) {
    var q: array<i32, 64>;
    let emax = decode_block_ints(b, &q);
    let c = block_coords(b) * 4u;
    let d = stream.dims;
    let n = min(vec3u(4u), d - c);
    for (var z = 0u; z < n.z; z++) {
      for (var y = 0u; y < n.y; y++) {
        let row = c.x + d.x * (c.y + y + d.y * (c.z + z - errparams.input_z));
        for (var x = 0u; x < n.x; x++) {
          let decoded = bitcast<f32>(int_to_float_bits(q[16u * z + 4u * y + x], emax));
          let e = abs(decoded - bitcast<f32>(load_value(row + x)));
          sum += e * e;
          largest = max(largest, e);
        }
      }
    }
  }
  if (largest > 0.0) { atomicMax(&error_max[0], bitcast<u32>(largest)); }
  wg_sums[lid] = sum;
  for (var s = 32u; s > 0u; s >>= 1u) {
    workgroupBarrier();
    if (lid < s) { wg_sums[lid] += wg_sums[lid + s]; }
  }
  if (lid == 0u) { error_sums[errparams.sum_base + grid_workgroup_index(wid, nwg)] = wg_sums[0]; }
}
