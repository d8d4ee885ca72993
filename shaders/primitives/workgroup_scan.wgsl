// Workgroup-wide exclusive scan of one u32 per invocation, for the GPU-path
// kernels (scan_tiled.wgsl): Kogge-Stone in workgroup memory, for devices
// without subgroups or when they are switched off. Its twin with the same
// names, workgroup_scan_subgroups.wgsl, is composed instead where the device
// has subgroups. WG is a const prepended by the host (tileConstants).

/**
 * The invocation's place in the workgroup's order (which column of the tile
 * it owns, where its sum goes in the scan): here its local index. Every
 * invocation must call it, in uniform control flow.
 */
fn lane_order(lid: u32) -> u32 {
  return lid;
}

// Ping-pong halves: one barrier per step.
var<workgroup> partial: array<u32, 2u * WG>;

/**
 * Exclusive scan of x over the workgroup in lane_order. Every invocation
 * must call it, in uniform control flow; it leaves `partial` in use, so a
 * kernel calls it once.
 */
fn workgroup_exclusive_scan(order: u32, x: u32) -> u32 {
  var v = x;
  var rd = 0u;
  partial[order] = v;
  workgroupBarrier();
  for (var d = 1u; d < WG; d <<= 1u) {
    if (order >= d) {
      v += partial[rd + order - d];
    }
    let wr = WG - rd;
    partial[wr + order] = v;
    rd = wr;
    workgroupBarrier();
  }
  return v - x;
}
