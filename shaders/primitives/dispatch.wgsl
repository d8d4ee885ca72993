// Indirect dispatch arguments from GPU-side counts. A "dispatch record" is 8
// u32 words in a params buffer: [n, units, capacity, count_in, x, y, z, extra].
// The host copies the count into count_in; `setup_dispatch` clamps it to
// capacity, counts units of work (chunks of elements, one per invocation)
// and writes the grid (x, y, z) that dispatchWorkgroupsIndirect reads at
// byte 16 of the record. Kernels read n and units as a uniform and skip
// invocations past `units` (the 2D grid can overshoot by less than a row).

override MAX_WG_PER_DIM: u32 = 65535u;

fn ceil_div(a: u32, b: u32) -> u32 {
  // Without the a + b - 1 overflow near 2^32.
  return a / b + select(0u, 1u, a % b != 0u);
}

/**
 * Workgroup grid covering `workgroups` with x, y <= MAX_WG_PER_DIM: 1D, then
 * 2D, and 3D only past MAX_WG_PER_DIM^2 (about 2^32 at the default limit, so
 * in practice only when tests lower the limit). x * y * z >= workgroups.
 */
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

/** Linear index of a workgroup in a dispatch_grid grid (x fastest, then y, then z). */
fn grid_workgroup_index(wid: vec3u, nwg: vec3u) -> u32 {
  return wid.x + nwg.x * (wid.y + nwg.y * wid.z);
}

/** Global invocation index in such a grid of WG-sized workgroups. */
fn grid_invocation_index(wid: vec3u, nwg: vec3u, lid: u32, wg: u32) -> u32 {
  return grid_workgroup_index(wid, nwg) * wg + lid;
}
