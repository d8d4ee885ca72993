// Multi-level exclusive scan of u32, barrier-free. Each invocation owns one
// chunk of CHUNK consecutive elements. `reduce` writes each chunk's sum to
// the next level; the top level (at most one chunk) is scanned by one
// invocation; `scan` then walks each chunk of a level serially from its carry
// (the scanned sum of all earlier chunks, from the level above). No
// workgroup memory, no barriers, no waiting between workgroups: see
// src/primitives/README.md for why (measured on SwiftShader).
// Level sizes come from dispatch records (setup.wgsl) bound as a uniform
// with a dynamic offset per level.
// Loops take four elements per iteration: per-iteration overhead dominates on
// CPU implementations (measured 1.5-2.5x on SwiftShader), and GPUs get more
// loads in flight.

override WG: u32 = 64u;
override CHUNK: u32 = 16u;

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

@compute @workgroup_size(WG)
fn reduce(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
          @builtin(local_invocation_index) lid: u32) {
  let c = grid_invocation_index(wid, nwg, lid, WG);
  if (c >= level.units) {
    return;
  }
  let begin = c * CHUNK;
  let len = min(level.n - begin, CHUNK);
  var sum = 0u;
  var j = 0u;
  for (; j + 4u <= len; j += 4u) {
    let i = begin + j;
    sum += (src[i] + src[i + 1u]) + (src[i + 2u] + src[i + 3u]);
  }
  for (; j < len; j++) {
    sum += src[begin + j];
  }
  dst[c] = sum;
}

@compute @workgroup_size(WG)
fn scan(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
        @builtin(local_invocation_index) lid: u32) {
  let c = grid_invocation_index(wid, nwg, lid, WG);
  // The top level is dispatched directly, also for n = 0, so that the total
  // (0) is still written.
  let units = max(level.units, 1u);
  if (c >= units) {
    return;
  }
  let begin = c * CHUNK;
  let len = min(level.n - begin, CHUNK);
  var run = carry[c];
  var j = 0u;
  for (; j + 4u <= len; j += 4u) {
    let i = begin + j;
    let v = vec4u(src[i], src[i + 1u], src[i + 2u], src[i + 3u]);
    dst[i] = run;
    dst[i + 1u] = run + v.x;
    dst[i + 2u] = run + v.x + v.y;
    dst[i + 3u] = run + v.x + v.y + v.z;
    run += (v.x + v.y) + (v.z + v.w);
  }
  for (; j < len; j++) {
    let v = src[begin + j];
    dst[begin + j] = run;
    run += v;
  }
  // The last chunk's carry plus its sum is the total of the level, which
  // equals the total of level 0; every level writes the same value.
  if (c == units - 1u) {
    total[0] = run;
  }
}
