// [min, max] per listed slot of a chunk pool over its blocks' ranges (block
// ids slot * B .. slot * B + B - 1, B = blocks per chunk): the range of the
// values its chunk decodes to, what a stream learns of a brick as it arrives
// (src/store/learnt-ranges.ts). Read back as 8 bytes per slot instead of 8
// per block. One workgroup per slot, strided over the grid.

struct SlotRangeParams {
  count: u32,             // slots listed
  blocks_per_chunk: u32,
  _pad0: u32,
  _pad1: u32,
}

@group(0) @binding(0) var<storage, read> block_ranges: array<vec2f>;
@group(0) @binding(1) var<storage, read> slot_list: array<u32>;
@group(0) @binding(2) var<uniform> slot_params: SlotRangeParams;
@group(0) @binding(3) var<storage, read_write> slot_ranges: array<vec2f>;

var<workgroup> lo_part: array<f32, 64>;
var<workgroup> hi_part: array<f32, 64>;

@compute @workgroup_size(64)
fn slot_ranges_of(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                  @builtin(local_invocation_index) lid: u32) {
  for (var i = wid.x; i < slot_params.count; i += nwg.x) {
    let base = slot_list[i] * slot_params.blocks_per_chunk;
    // the empty range: a block with no voxel in the volume, or a slot without a finite value
    var lo = 3.4028234663852886e38;
    var hi = -3.4028234663852886e38;
    for (var b = lid; b < slot_params.blocks_per_chunk; b += 64u) {
      let r = block_ranges[base + b];
      lo = min(lo, r.x);
      hi = max(hi, r.y);
    }
    lo_part[lid] = lo;
    hi_part[lid] = hi;
    workgroupBarrier();
    for (var s = 32u; s > 0u; s >>= 1u) {
      if (lid < s) {
        lo_part[lid] = min(lo_part[lid], lo_part[lid + s]);
        hi_part[lid] = max(hi_part[lid], hi_part[lid + s]);
      }
      workgroupBarrier();
    }
    if (lid == 0u) {
      slot_ranges[i] = vec2f(lo_part[0], hi_part[0]);
    }
    workgroupBarrier();
  }
}
