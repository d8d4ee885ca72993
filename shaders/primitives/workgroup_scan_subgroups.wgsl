enable subgroups;

// Workgroup-wide exclusive scan of one u32 per invocation with subgroup
// operations: the twin of workgroup_scan.wgsl (same names), composed first
// (it carries the `enable` directive) only on devices with the 'subgroups'
// feature. Each subgroup scans its invocations with subgroupInclusiveAdd;
// the last invocation of each subgroup stores the subgroup's total; after
// one barrier each subgroup adds up the totals of the subgroups before it,
// subgroup_size of them per step (a single step unless
// subgroup_size^2 < WG), and subgroupAdd combines the steps. One barrier
// instead of log2(WG).
//
// The subgroup size is read from the builtin, never assumed: any size from
// 4 to 128 works (SwiftShader's is 4). Subgroups are assumed to be
// consecutive runs of local_invocation_index (subgroup q holds
// q * subgroup_size + subgroup_invocation_id), which is what Dawn, wgpu and
// the drivers do for one-dimensional workgroups though WGSL does not promise
// it; the tests compare against a CPU scan on every size.

struct Lane {
  @builtin(local_invocation_index) lid: u32,
  @builtin(subgroup_size) sg_size: u32,
  @builtin(subgroup_invocation_id) sg_lane: u32,
}

// One total per subgroup; a subgroup has at least 4 invocations.
var<workgroup> subgroup_totals: array<u32, (WG + 3u) / 4u>;

/**
 * Exclusive scan of x over the workgroup, in local_invocation_index order.
 * Every invocation must call it, in uniform control flow; it leaves
 * `subgroup_totals` in use, so a kernel calls it once.
 */
fn workgroup_exclusive_scan(inv: Lane, x: u32) -> u32 {
  let inclusive = subgroupInclusiveAdd(x);
  let sg = inv.lid / inv.sg_size;
  // The last invocation of a subgroup holds the subgroup's total. Only the
  // workgroup's last subgroup can be partial, and nobody reads its total.
  if (inv.sg_lane == inv.sg_size - 1u) {
    subgroup_totals[sg] = inclusive;
  }
  workgroupBarrier();
  var before = 0u;
  for (var k = inv.sg_lane; k < sg; k += inv.sg_size) {
    before += subgroup_totals[k];
  }
  return subgroupAdd(before) + inclusive - x;
}
