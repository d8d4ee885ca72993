enable subgroups;

// Workgroup-wide exclusive scan of one u32 per invocation with subgroup
// operations: the twin of workgroup_scan.wgsl (same names), composed first
// (it carries the `enable` directive) only on devices with the 'subgroups'
// feature. Nothing is assumed about the subgroup size (any, read from the
// subgroup operations themselves) or about which invocations form a
// subgroup (WGSL does not tie subgroups to local_invocation_index): each
// subgroup takes a run of consecutive places in the workgroup's order from
// a workgroup atomic, its invocations in subgroup order, so a subgroup scan
// is a piece of the workgroup scan. The scan: subgroupInclusiveAdd within
// each subgroup; one invocation per subgroup stores the subgroup's first
// place and total; after one barrier each subgroup adds up the totals of
// the subgroups placed before it, as many per step as it has invocations,
// combined with subgroupAdd. One barrier instead of log2(WG).

var<workgroup> places_taken: atomic<u32>;
var<workgroup> subgroups_seen: atomic<u32>;
// Per subgroup (a subgroup has at least 4 invocations, only the last one
// placed may be partial): its first place and its total.
var<workgroup> subgroup_first: array<u32, (WG + 3u) / 4u>;
var<workgroup> subgroup_totals: array<u32, (WG + 3u) / 4u>;

/**
 * The invocation's place in the workgroup's order (which column of the tile
 * it owns, where its sum goes in the scan). Every invocation must call it,
 * once, in uniform control flow.
 */
fn lane_order(lid: u32) -> u32 {
  let size = subgroupAdd(1u);
  var first = 0u;
  if (subgroupElect()) {
    first = atomicAdd(&places_taken, size);
  }
  return subgroupBroadcastFirst(first) + subgroupExclusiveAdd(1u);
}

/**
 * Exclusive scan of x over the workgroup in lane_order. Every invocation
 * must call it, in uniform control flow; it leaves the subgroup tables in
 * use, so a kernel calls it once.
 */
fn workgroup_exclusive_scan(order: u32, x: u32) -> u32 {
  let rank = subgroupExclusiveAdd(1u);
  let size = subgroupAdd(1u);
  let first = order - rank;
  let inclusive = subgroupInclusiveAdd(x);
  let total = subgroupAdd(x);
  if (subgroupElect()) {
    let s = atomicAdd(&subgroups_seen, 1u);
    subgroup_first[s] = first;
    subgroup_totals[s] = total;
  }
  workgroupBarrier();
  let seen = atomicLoad(&subgroups_seen);
  var before = 0u;
  for (var k = rank; k < seen; k += size) {
    if (subgroup_first[k] < first) {
      before += subgroup_totals[k];
    }
  }
  return subgroupAdd(before) + inclusive - x;
}
