// The LRU block cache (paper Algorithm 1) between the primitives, in work
// proportional to the active and new blocks, not to the capacity. Every
// dispatch is indirect, sized by the plan kernels from GPU counts; when the
// cache is too small for the surface the counts are 0 and the cache state is
// left as it was (see plan.wgsl).
//
// State: slot_to_block[slot] (NONE = empty), block_to_slot[block] (NONE =
// not cached), and the LRU order as a log: positions [0, tail) of `log` hold
// slots, least recently used first; `valid[p]` says whether position p is a
// slot's current entry (each slot has exactly one valid entry; a slot used
// again gets a new entry at the tail and its old one becomes a hole).
// `tree` counts valid entries: a 16-ary tree over the P = log size positions
// (level k >= 1 has max(1, P >> 4k) nodes, node j covering positions
// [j << 4k, (j + 1) << 4k); the levels stored one after the other, the
// leaves being `valid` itself), so the r-th least recently used slot is found
// by one descent (at most 16 reads per level) and an entry changes by one
// atomic per level (5 levels for a million positions).
// Per computation: hits invalidate their entry (mark_cached), the i-th new
// block takes the i-th valid entry's slot (pick_victims, assign_slots, which
// invalidates it), and every active slot is appended in active-list order
// (append_log). When the log is full it is compacted (scan + compaction of
// the valid entries, then rebuild_log): amortized over the >= slots
// computations' worth of appends since the last one.

fn tree_level_nodes(log_size: u32, k: u32) -> u32 {
  return max(1u, log_size >> (4u * k));
}

// Levels above the leaves: up to the first level with a single node.
fn tree_levels(log_size: u32) -> u32 {
  var k = 1u;
  while (tree_level_nodes(log_size, k) > 1u) {
    k++;
  }
  return k;
}

// ---- mark_cached: per entry i of the active list, a cached block's log
// entry becomes a hole (it is appended again at the tail); an uncached one
// is new (new_mask[i] = 1).
@group(0) @binding(0) var<storage, read> mark_counters: array<u32>;
@group(0) @binding(1) var<storage, read> mark_active_ids: array<u32>;
@group(0) @binding(2) var<storage, read> mark_block_to_slot: array<u32>;
@group(0) @binding(3) var<storage, read> mark_slot_pos: array<u32>;
@group(0) @binding(4) var<storage, read_write> mark_valid: array<u32>;
@group(0) @binding(5) var<storage, read_write> mark_tree: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> mark_new_mask: array<u32>;

@compute @workgroup_size(64)
fn mark_cached(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
               @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, 64u);
  if (i >= mark_counters[C_ACTIVE_GATED]) {
    return;
  }
  let slot = mark_block_to_slot[mark_active_ids[i]];
  if (slot != NONE) {
    let p = mark_slot_pos[slot];
    mark_valid[p] = 0u;
    let log_size = mark_counters[C_LOG_SIZE];
    let levels = tree_levels(log_size);
    var at = 0u;
    for (var k = 1u; k <= levels; k++) {
      atomicSub(&mark_tree[at + (p >> (4u * k))], 1u);
      at += tree_level_nodes(log_size, k);
    }
  }
  mark_new_mask[i] = select(0u, 1u, slot == NONE);
}

// ---- pick_victims: new block i takes the slot of the (i + 1)-th valid log
// entry (least recently used first; hits are holes by now). Read only.
@group(0) @binding(0) var<storage, read> pick_counters: array<u32>;
@group(0) @binding(1) var<storage, read> pick_tree: array<u32>;
@group(0) @binding(2) var<storage, read> pick_log: array<u32>;
@group(0) @binding(3) var<storage, read_write> pick_victims: array<u32>;
@group(0) @binding(4) var<storage, read> pick_valid: array<u32>;

@compute @workgroup_size(64)
fn pick_victims_of_new(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                       @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, 64u);
  if (i >= pick_counters[C_NEW]) {
    return;
  }
  let log_size = pick_counters[C_LOG_SIZE];
  let levels = tree_levels(log_size);
  var rank = i + 1u;
  var j = 0u; // the root: node 0 of the top level
  for (var k = levels; k >= 1u; k--) {
    // node j of level k: its children are nodes 16j .. 16j + 15 of level k - 1
    var below = 0u; // where level k - 1 starts in `tree` (k - 1 >= 1)
    for (var m = 1u; m + 1u < k; m++) {
      below += tree_level_nodes(log_size, m);
    }
    let children = select(tree_level_nodes(log_size, k - 1u), log_size, k == 1u);
    var chosen = 16u * j;
    for (var c = 0u; c < 16u; c++) {
      let child = 16u * j + c;
      if (child >= children) {
        break;
      }
      let count = select(pick_tree[below + child], pick_valid[child], k == 1u);
      chosen = child;
      if (rank <= count) {
        break;
      }
      rank -= count;
    }
    j = chosen;
  }
  pick_victims[i] = pick_log[j];
}

// ---- assign_slots: new block new_ids[i] goes to slot victims[i], evicting
// the block that was there; the slot's log entry becomes a hole (append_log
// gives it a new one). Evicted blocks are cached, new ones are not, so no two
// invocations write the same block_to_slot entry.
@group(0) @binding(0) var<storage, read> assign_counters: array<u32>;
@group(0) @binding(1) var<storage, read> assign_new_ids: array<u32>;
@group(0) @binding(2) var<storage, read> assign_victims: array<u32>;
@group(0) @binding(3) var<storage, read_write> assign_slot_to_block: array<u32>;
@group(0) @binding(4) var<storage, read_write> assign_block_to_slot: array<u32>;
@group(0) @binding(5) var<storage, read> assign_slot_pos: array<u32>;
@group(0) @binding(6) var<storage, read_write> assign_valid: array<u32>;
@group(0) @binding(7) var<storage, read_write> assign_tree: array<atomic<u32>>;

@compute @workgroup_size(64)
fn assign_slots(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, 64u);
  if (i >= assign_counters[C_NEW]) {
    return;
  }
  let slot = assign_victims[i];
  let evicted = assign_slot_to_block[slot];
  if (evicted != NONE) {
    assign_block_to_slot[evicted] = NONE;
  }
  let b = assign_new_ids[i];
  assign_slot_to_block[slot] = b;
  assign_block_to_slot[b] = slot;
  let p = assign_slot_pos[slot];
  assign_valid[p] = 0u;
  let log_size = assign_counters[C_LOG_SIZE];
  let levels = tree_levels(log_size);
  var at = 0u;
  for (var k = 1u; k <= levels; k++) {
    atomicSub(&assign_tree[at + (p >> (4u * k))], 1u);
    at += tree_level_nodes(log_size, k);
  }
}

// ---- append_log: active entry i's slot (every active block is cached now)
// gets log position base + i: the most recently used, in active-list order.
@group(0) @binding(0) var<storage, read> append_counters: array<u32>;
@group(0) @binding(1) var<storage, read> append_active_ids: array<u32>;
@group(0) @binding(2) var<storage, read> append_block_to_slot: array<u32>;
@group(0) @binding(3) var<storage, read_write> append_log: array<u32>;
@group(0) @binding(4) var<storage, read_write> append_slot_pos: array<u32>;
@group(0) @binding(5) var<storage, read_write> append_valid: array<u32>;
@group(0) @binding(6) var<storage, read_write> append_tree: array<atomic<u32>>;

@compute @workgroup_size(64)
fn append_active(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                 @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, 64u);
  if (i >= append_counters[C_ACTIVE_GATED]) {
    return;
  }
  let slot = append_block_to_slot[append_active_ids[i]];
  let p = append_counters[C_LOG_BASE] + i;
  append_log[p] = slot;
  append_slot_pos[slot] = p;
  append_valid[p] = 1u;
  let log_size = append_counters[C_LOG_SIZE];
  let levels = tree_levels(log_size);
  var at = 0u;
  for (var k = 1u; k <= levels; k++) {
    atomicAdd(&append_tree[at + (p >> (4u * k))], 1u);
    at += tree_level_nodes(log_size, k);
  }
}

// ---- rebuild_log: the log becomes [fresh slots first_fresh, first_fresh + 1,
// ...] followed by the `kept` entries compacted into log_scratch (in order),
// every other position a hole; slot positions and the tree follow (a node's
// count is how much of its range lies below fresh + kept). Used after a
// compaction (fresh 0), for an emptied cache (kept 0) and after growth (the
// new slots first). One invocation per index in [0, 2 x log size).
struct RebuildParams {
  fresh: u32,
  first_fresh: u32,
  use_kept: u32,  // 1: kept = counters[C_LOG_VALID]; 0: kept = 0
}

@group(0) @binding(0) var<uniform> rebuild: RebuildParams;
@group(0) @binding(2) var<storage, read> rebuild_scratch: array<u32>;
@group(0) @binding(3) var<storage, read_write> rebuild_log_entries: array<u32>;
@group(0) @binding(4) var<storage, read_write> rebuild_slot_pos: array<u32>;
@group(0) @binding(5) var<storage, read_write> rebuild_valid: array<u32>;
@group(0) @binding(6) var<storage, read_write> rebuild_tree: array<u32>;

fn rebuild_entry(k: u32, log_size: u32, kept: u32) {
  let entries = rebuild.fresh + kept;
  if (k < log_size) {
    var slot = NONE;
    if (k < rebuild.fresh) {
      slot = rebuild.first_fresh + k;
    } else if (k < entries) {
      slot = rebuild_scratch[k - rebuild.fresh];
    }
    rebuild_log_entries[k] = slot;
    rebuild_valid[k] = select(0u, 1u, k < entries);
    if (slot != NONE) {
      rebuild_slot_pos[slot] = k;
    }
  }
  // Tree node k (flat index): find its level, then its range of positions.
  var first = 0u;
  var level = 1u;
  let levels = tree_levels(log_size);
  loop {
    let nodes = tree_level_nodes(log_size, level);
    if (k < first + nodes) {
      let lo = (k - first) << (4u * level);
      let span = min(1u << (4u * level), log_size);
      rebuild_tree[k] = select(0u, min(entries - lo, span), entries > lo);
      return;
    }
    first += nodes;
    level++;
    if (level > levels) {
      return;
    }
  }
}

// Reset and growth (direct dispatch): also moves the tail.
@group(0) @binding(1) var<storage, read_write> rebuild_counters: array<u32>;

@compute @workgroup_size(64)
fn rebuild_log(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
               @builtin(local_invocation_index) lid: u32) {
  let k = grid_invocation_index(wid, nwg, lid, 64u);
  let log_size = rebuild_counters[C_LOG_SIZE];
  if (k >= 2u * log_size) {
    return;
  }
  let kept = select(0u, rebuild_counters[C_LOG_VALID], rebuild.use_kept != 0u);
  rebuild_entry(k, log_size, kept);
  if (k == 0u) {
    rebuild_counters[C_LOG_TAIL] = rebuild.fresh + kept;
  }
}

// After a compaction within a computation (indirect dispatch from the
// counters, so they are bound read-only here; plan_update moves the tail).
@group(0) @binding(1) var<storage, read> compacted_counters: array<u32>;

@compute @workgroup_size(64)
fn rebuild_log_compacted(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                         @builtin(local_invocation_index) lid: u32) {
  let k = grid_invocation_index(wid, nwg, lid, 64u);
  let log_size = compacted_counters[C_LOG_SIZE];
  if (k >= 2u * log_size) {
    return;
  }
  rebuild_entry(k, log_size, compacted_counters[C_LOG_VALID]);
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

// ---- forget_slots: a chunk pool's slot got another chunk (or none): the
// blocks decoded from its old chunk are forgotten, so a pool id never names
// a stale block (blocks_pool.wgsl). Entry i: block i % per_chunk of the slot
// in list entry i / per_chunk. The cache slot keeps its log entry (it is
// reused in LRU order: assign_slots skips an empty slot's old block).
struct ForgetParams {
  count: u32,      // entries of the list
  per_chunk: u32,  // block ids per pool slot
  pad0: u32,
  pad1: u32,
}

@group(0) @binding(0) var<storage, read> forget_list: array<vec2u>;
@group(0) @binding(1) var<uniform> forget: ForgetParams;
@group(0) @binding(2) var<storage, read_write> forget_block_to_slot: array<u32>;
@group(0) @binding(3) var<storage, read_write> forget_slot_to_block: array<u32>;

@compute @workgroup_size(64)
fn forget_slots(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
                @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, 64u);
  if (i >= forget.count * forget.per_chunk) {
    return;
  }
  let b = forget_list[i / forget.per_chunk].x * forget.per_chunk + i % forget.per_chunk;
  let slot = forget_block_to_slot[b];
  if (slot != NONE) {
    forget_slot_to_block[slot] = NONE;
    forget_block_to_slot[b] = NONE;
  }
}
