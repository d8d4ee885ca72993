// The LRU block cache (paper Algorithm 1) between the primitives: slot ages,
// marking new blocks and available slots, assigning slots. Every dispatch is
// indirect, sized by the plan kernels from GPU counts; when the cache is too
// small for the surface the counts are 0 and the cache state is left as it
// was (see plan.wgsl).
//
// State: slot_age[slot] (NONE for an empty slot, else 0..AGE_MAX),
// slot_to_block[slot] (NONE = empty), block_to_slot[block] (NONE = not cached).

// ---- age_slots: every slot ages by one (saturating; empty slots keep NONE)
// and starts out available.
@group(0) @binding(0) var<storage, read> age_counters: array<u32>;
@group(0) @binding(1) var<storage, read> age_slot_to_block: array<u32>;
@group(0) @binding(2) var<storage, read_write> age_slot_age: array<u32>;
@group(0) @binding(3) var<storage, read_write> age_avail_mask: array<u32>;

@compute @workgroup_size(64)
fn age_slots(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
             @builtin(local_invocation_index) lid: u32) {
  let s = grid_invocation_index(wid, nwg, lid, 64u);
  if (s >= age_counters[C_SLOTS_GATED]) {
    return;
  }
  if (age_slot_to_block[s] != NONE) {
    age_slot_age[s] = min(age_slot_age[s] + 1u, AGE_MAX);
  }
  age_avail_mask[s] = 1u;
}

// ---- mark_cached: per entry i of the active list, a cached block makes its
// slot young and unavailable; an uncached one is new (new_mask[i] = 1).
@group(0) @binding(0) var<storage, read> mark_counters: array<u32>;
@group(0) @binding(1) var<storage, read> mark_active_ids: array<u32>;
@group(0) @binding(2) var<storage, read> mark_block_to_slot: array<u32>;
@group(0) @binding(3) var<storage, read_write> mark_slot_age: array<u32>;
@group(0) @binding(4) var<storage, read_write> mark_avail_mask: array<u32>;
@group(0) @binding(5) var<storage, read_write> mark_new_mask: array<u32>;

@compute @workgroup_size(64)
fn mark_cached(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
               @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, 64u);
  if (i >= mark_counters[C_ACTIVE_GATED]) {
    return;
  }
  let slot = mark_block_to_slot[mark_active_ids[i]];
  if (slot != NONE) {
    mark_slot_age[slot] = 0u;
    mark_avail_mask[slot] = 0u;
  }
  mark_new_mask[i] = select(0u, 1u, slot == NONE);
}

// ---- assign_slots: new block new_ids[i] goes to slot avail_sorted[i] (the
// i-th oldest available slot), evicting the block that was there. Evicted
// blocks are cached, new ones are not, so no two invocations write the same
// block_to_slot entry. (The count of slots in use is kept by plan_update:
// empty slots sort first, so the new blocks fill them first.)
@group(0) @binding(0) var<storage, read> assign_counters: array<u32>;
@group(0) @binding(1) var<storage, read> assign_new_ids: array<u32>;
@group(0) @binding(2) var<storage, read> assign_avail_sorted: array<u32>;
@group(0) @binding(3) var<storage, read_write> assign_slot_to_block: array<u32>;
@group(0) @binding(4) var<storage, read_write> assign_block_to_slot: array<u32>;
@group(0) @binding(5) var<storage, read_write> assign_slot_age: array<u32>;

@compute @workgroup_size(64)
fn assign_slots(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, 64u);
  if (i >= assign_counters[C_NEW]) {
    return;
  }
  let slot = assign_avail_sorted[i];
  let evicted = assign_slot_to_block[slot];
  if (evicted != NONE) {
    assign_block_to_slot[evicted] = NONE;
  }
  let b = assign_new_ids[i];
  assign_slot_to_block[slot] = b;
  assign_block_to_slot[b] = slot;
  assign_slot_age[slot] = 0u;
}

// ---- fill_none: words [begin, end) of a buffer become NONE (emptying the
// cache, and the new slots after growth). Direct dispatch, count from the host.
struct FillRange {
  begin: u32,
  end: u32,
}

@group(0) @binding(0) var<uniform> fill_range: FillRange;
@group(0) @binding(1) var<storage, read_write> fill_target: array<u32>;

@compute @workgroup_size(64)
fn fill_none(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
             @builtin(local_invocation_index) lid: u32) {
  let i = fill_range.begin + grid_invocation_index(wid, nwg, lid, 64u);
  if (i < fill_range.end) {
    fill_target[i] = NONE;
  }
}
