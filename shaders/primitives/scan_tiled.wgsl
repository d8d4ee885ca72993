// Multi-level exclusive scan of u32, GPU path (src/primitives/README.md).
// One workgroup of WG invocations owns a tile of TILE = WG * ITEMS
// consecutive elements; the invocation at place `lid` in the workgroup's
// order (lane_order: its local index, or with subgroups a place handed out
// per subgroup) loads and stores elements tile_base + k * WG + lid
// (consecutive invocations on consecutive words: coalesced). `reduce` writes each tile's sum to the next level; the top
// level (at most one tile) is scanned by one workgroup; `scan` then scans
// each tile of a level in workgroup memory from its carry (the scanned sum
// of all earlier tiles, from the level above). WG, ITEMS and TILE are consts
// prepended by the host (tileConstants); level sizes come from dispatch
// records (setup.wgsl, with one unit = one tile = one workgroup). The
// workgroup-wide scan of the invocations' sums (workgroup_exclusive_scan and
// lane_order) comes from workgroup_scan.wgsl or, on devices with subgroups,
// workgroup_scan_subgroups.wgsl.
// Barriers are only reached in uniform control flow: the early return
// depends on the workgroup index and a uniform, both uniform across a
// workgroup.

struct Level {
  n: u32,
  units: u32,
  capacity: u32,
  count_in: u32,
}

@group(0) @binding(0) var<uniform> level: Level;
@group(0) @binding(1) var<storage, read> src: array<u32>;
@group(0) @binding(2) var<storage, read_write> dst: array<u32>;
@group(0) @binding(3) var<storage, read> carry: array<u32>;
@group(0) @binding(4) var<storage, read_write> total: array<u32>;

// The tile, one padding word per 32 so that invocation lid reading its ITEMS
// consecutive words (stride ITEMS across lanes) avoids bank conflicts.
var<workgroup> tile: array<u32, TILE + TILE / 32u + 1u>;

fn padded(i: u32) -> u32 {
  return i + (i >> 5u);
}

@compute @workgroup_size(WG)
fn reduce(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
          @builtin(local_invocation_index) local_index: u32) {
  let t = grid_workgroup_index(wid, nwg);
  if (t >= level.units) {
    return;
  }
  let lid = lane_order(local_index);
  let base = t * TILE;
  var sum = 0u;
  for (var k = 0u; k < ITEMS; k++) {
    let i = base + k * WG + lid;
    if (i < level.n) {
      sum += src[i];
    }
  }
  let before = workgroup_exclusive_scan(lid, sum);
  if (lid == WG - 1u) {
    dst[t] = before + sum;
  }
}

@compute @workgroup_size(WG)
fn scan(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
        @builtin(local_invocation_index) local_index: u32) {
  let t = grid_workgroup_index(wid, nwg);
  // The top level is dispatched directly, also for n = 0, so that the total
  // (0) is still written.
  let units = max(level.units, 1u);
  if (t >= units) {
    return;
  }
  let lid = lane_order(local_index);
  let base = t * TILE;
  for (var k = 0u; k < ITEMS; k++) {
    let j = k * WG + lid;
    var v = 0u;
    if (base + j < level.n) {
      v = src[base + j];
    }
    tile[padded(j)] = v;
  }
  workgroupBarrier();
  // Each invocation scans its ITEMS consecutive elements serially...
  let first = lid * ITEMS;
  var run = 0u;
  for (var k = 0u; k < ITEMS; k++) {
    let p = padded(first + k);
    let v = tile[p];
    tile[p] = run;
    run += v;
  }
  // ...then the invocations' sums are scanned across the workgroup.
  let tile_carry = carry[t];
  let before = workgroup_exclusive_scan(lid, run) + tile_carry;
  for (var k = 0u; k < ITEMS; k++) {
    tile[padded(first + k)] += before;
  }
  workgroupBarrier();
  for (var k = 0u; k < ITEMS; k++) {
    let j = k * WG + lid;
    if (base + j < level.n) {
      dst[base + j] = tile[padded(j)];
    }
  }
  // The last tile's carry plus its sum is the total of the level, which
  // equals the total of level 0; every level writes the same value.
  if (t == units - 1u && lid == WG - 1u) {
    total[0] = before + run;
  }
}
