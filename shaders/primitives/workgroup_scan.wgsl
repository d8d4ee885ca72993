// Workgroup-wide exclusive scan of one u32 per invocation, for the GPU-path
// kernels (scan_tiled.wgsl): Kogge-Stone in workgroup memory, for devices
// without subgroups or when they are switched off. Its twin with the same
// names, workgroup_scan_subgroups.wgsl, is composed instead where the device
// has subgroups. WG is a const prepended by the host (tileConstants).

/**
 * The invocation's own builtins, one parameter of a tile kernel (the subgroup
 * twin adds the subgroup ones). Workgroup ids stay separate parameters: a
 * struct holding any non-uniform builtin is non-uniform as a whole.
 */
struct Lane {
  @builtin(local_invocation_index) lid: u32,
}

// Ping-pong halves: one barrier per step.
var<workgroup> partial: array<u32, 2u * WG>;

/**
 * Exclusive scan of x over the workgroup, in local_invocation_index order.
 * Every invocation must call it, in uniform control flow; it leaves
 * `partial` in use, so a kernel calls it once.
 */
fn workgroup_exclusive_scan(inv: Lane, x: u32) -> u32 {
  let lid = inv.lid;
  var v = x;
  var rd = 0u;
  partial[lid] = v;
  workgroupBarrier();
  for (var d = 1u; d < WG; d <<= 1u) {
    if (lid >= d) {
      v += partial[rd + lid - d];
    }
    let wr = WG - rd;
    partial[wr + lid] = v;
    rd = wr;
    workgroupBarrier();
  }
  return v - x;
}
