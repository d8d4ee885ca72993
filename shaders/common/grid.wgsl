// Dispatch grids: the one layout of workgroups every kernel of the project
// uses (src/gpu/dispatch.ts `dispatchGrid` is its host twin). `workgroups`
// linear workgroups become (x, 1, 1) up to MAX_WG_PER_DIM, then (x, y, 1)
// with x, y <= MAX_WG_PER_DIM, and z > 1 only past MAX_WG_PER_DIM^2 (about
// 2^32 at the default limit, so in practice only when tests lower the
// limit). x * y * z >= workgroups: kernels rebuild their linear index with
// grid_workgroup_index (x fastest, then y, then z) and skip indices past
// their count.

override MAX_WG_PER_DIM: u32 = 65535u;

fn ceil_div(a: u32, b: u32) -> u32 {
  // Without the a + b - 1 overflow near 2^32.
  return a / b + select(0u, 1u, a % b != 0u);
}

/** The grid for `workgroups` (what a kernel writing indirect arguments writes). */
fn dispatch_grid(workgroups: u32) -> vec3u {
  if (workgroups <= MAX_WG_PER_DIM) {
    return vec3u(workgroups, 1u, 1u);
  }
  let plane = MAX_WG_PER_DIM * MAX_WG_PER_DIM;
  let z = ceil_div(workgroups, plane);
  let rest = ceil_div(workgroups, z);
  let y = ceil_div(rest, MAX_WG_PER_DIM);
  return vec3u(ceil_div(rest, y), y, z);
}

/** Linear index of a workgroup in such a grid (x fastest, then y, then z). */
fn grid_workgroup_index(wid: vec3u, nwg: vec3u) -> u32 {
  return wid.x + nwg.x * (wid.y + nwg.y * wid.z);
}

/** Global invocation index in such a grid of `wg`-invocation workgroups. */
fn grid_invocation_index(wid: vec3u, nwg: vec3u, lid: u32, wg: u32) -> u32 {
  return grid_workgroup_index(wid, nwg) * wg + lid;
}
