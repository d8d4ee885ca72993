// Stream compaction, GPU path: the scan's tile layout (scan_tiled.wgsl).
// Workgroup t owns elements t * TILE + k * WG + lid (k < ITEMS): consecutive
// invocations read consecutive mask, offsets and value words (coalesced),
// and each kept element goes to out[offsets[i]], so kept neighbours write
// neighbouring words too. No workgroup memory or barriers are needed. WG,
// ITEMS and TILE are consts prepended by the host; n and the number of
// tiles come from a dispatch record (one unit = one tile = one workgroup).

struct Dispatch {
  n: u32,
  units: u32,
  capacity: u32,
  count_in: u32,
}

@group(0) @binding(0) var<uniform> dispatch: Dispatch;
@group(0) @binding(1) var<storage, read> mask: array<u32>;
@group(0) @binding(2) var<storage, read> offsets: array<u32>;
@group(0) @binding(3) var<storage, read> values: array<u32>;
@group(0) @binding(4) var<storage, read_write> out: array<u32>;

@compute @workgroup_size(WG)
fn compact_values(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                  @builtin(local_invocation_index) lid: u32) {
  let t = grid_workgroup_index(wid, nwg);
  if (t >= dispatch.units) {
    return;
  }
  for (var k = 0u; k < ITEMS; k++) {
    let i = t * TILE + k * WG + lid;
    if (i < dispatch.n && mask[i] != 0u) {
      out[offsets[i]] = values[i];
    }
  }
}

// Written out again rather than shared: a shared function taking a flag
// would make this entry point statically use `values` (see compact.wgsl).
@compute @workgroup_size(WG)
fn compact_ids(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
               @builtin(local_invocation_index) lid: u32) {
  let t = grid_workgroup_index(wid, nwg);
  if (t >= dispatch.units) {
    return;
  }
  for (var k = 0u; k < ITEMS; k++) {
    let i = t * TILE + k * WG + lid;
    if (i < dispatch.n && mask[i] != 0u) {
      out[offsets[i]] = i;
    }
  }
}
