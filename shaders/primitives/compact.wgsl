// Stream compaction by a 0/1 mask and its exclusive scan: every set element
// i < n goes to out[offsets[i]]; `compact_values` writes values[i],
// `compact_ids` writes i (the paper's StreamCompactIDs). Order does not
// matter here, so a workgroup covers WG * CHUNK elements with adjacent
// invocations on adjacent elements (coalesced on GPUs). n comes from a
// dispatch record (dispatch.wgsl); the grid is sized from it on the GPU.

override WG: u32 = 64u;
override CHUNK: u32 = 16u;

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

fn keep_value(i: u32, n: u32) {
  if (i < n && mask[i] != 0u) {
    out[offsets[i]] = values[i];
  }
}

fn keep_id(i: u32, n: u32) {
  if (i < n && mask[i] != 0u) {
    out[offsets[i]] = i;
  }
}

// Four elements per iteration: the loop overhead dominates on CPU
// implementations (SwiftShader), and GPUs get more loads in flight.
@compute @workgroup_size(WG)
fn compact_values(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                  @builtin(local_invocation_index) lid: u32) {
  let base = grid_workgroup_index(wid, nwg) * (WG * CHUNK) + lid;
  let n = dispatch.n;
  var k = 0u;
  for (; k + 4u <= CHUNK; k += 4u) {
    let i = base + k * WG;
    keep_value(i, n);
    keep_value(i + WG, n);
    keep_value(i + 2u * WG, n);
    keep_value(i + 3u * WG, n);
  }
  for (; k < CHUNK; k++) {
    keep_value(base + k * WG, n);
  }
}

@compute @workgroup_size(WG)
fn compact_ids(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
               @builtin(local_invocation_index) lid: u32) {
  let base = grid_workgroup_index(wid, nwg) * (WG * CHUNK) + lid;
  let n = dispatch.n;
  var k = 0u;
  for (; k + 4u <= CHUNK; k += 4u) {
    let i = base + k * WG;
    keep_id(i, n);
    keep_id(i + WG, n);
    keep_id(i + 2u * WG, n);
    keep_id(i + 3u * WG, n);
  }
  for (; k < CHUNK; k++) {
    keep_id(base + k * WG, n);
  }
}
