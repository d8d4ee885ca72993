// Plan kernels: one invocation each (argument kernels), run between the
// primitives to turn GPU counts into the gated counts and the indirect
// dispatch / draw arguments of what follows. This is where the pipeline
// "branches" without the host: a cache too small for the surface, or nothing
// new to decode, or more vertices than the buffers hold, all become
// dispatches of zero workgroups.

@group(0) @binding(0) var<storage, read_write> counters: array<u32>;

// Writes counters[at..at+3] directly: a ptr<storage> parameter would need
// WGSL's unrestricted_pointer_parameters, which naga (Firefox) rejects.
fn write_dispatch_args(at: u32, workgroups: u32) {
  let g = dispatch_grid(workgroups);
  counters[at] = g.x;
  counters[at + 1u] = g.y;
  counters[at + 2u] = g.z;
}

// After the active groups are counted: how many blocks of theirs to test.
@compute @workgroup_size(1)
fn plan_groups() {
  let blocks = counters[C_ACTIVE_GROUPS] * counters[C_GROUP_SIZE];
  counters[C_GROUP_BLOCKS] = blocks;
  write_dispatch_args(A_GROUP_BLOCKS, ceil_div(blocks, 64u));
}

// After the active list: is the cache large enough? The update succeeds iff
// new <= available, and available = slots - (active - new), so iff
// active <= slots: known before touching any cache state.
@compute @workgroup_size(1)
fn plan_cache() {
  let active_count = counters[C_ACTIVE];
  let slots = counters[C_SLOTS];
  let fits = active_count <= slots;
  let active_gated = select(0u, active_count, fits);
  let slots_gated = select(0u, slots, fits);
  counters[C_ACTIVE_GATED] = active_gated;
  counters[C_SLOTS_GATED] = slots_gated;
  counters[C_STATUS] = select(STATUS_CACHE_SHORTFALL, 0u, fits);
  // The LRU log must have room for this computation's appends: compact it
  // first when it has not (amortized: the log holds >= 2 x slots positions,
  // and a compaction leaves exactly `slots` entries).
  let log_size = counters[C_LOG_SIZE];
  let compact = fits && counters[C_LOG_TAIL] + active_gated > log_size;
  counters[C_LOG_COMPACT] = select(0u, counters[C_LOG_TAIL], compact);
  write_dispatch_args(A_SLOTS, ceil_div(select(0u, 2u * log_size, compact), 64u));
  write_dispatch_args(A_MARK, ceil_div(active_gated, 64u));
}

// After the scan of the new-block mask: "exit if n_new = 0" (the victim
// search and the assignment get count 0). Empty slots come first in the LRU
// log, so the new blocks fill min(new, empty) of them: that is how many more
// slots hold a block after the assignment.
@compute @workgroup_size(1)
fn plan_update() {
  let fresh = counters[C_NEW];
  counters[C_SLOTS_USED] = min(counters[C_SLOTS_USED] + fresh, counters[C_SLOTS]);
  counters[C_COMPACT_NEW] = select(0u, counters[C_ACTIVE_GATED], fresh > 0u);
  // After a log compaction (plan_cache, rebuild_log_compacted) the kept entries end the log.
  if (counters[C_LOG_COMPACT] > 0u) {
    counters[C_LOG_TAIL] = counters[C_LOG_VALID];
  }
  // This computation's active slots go to log positions [base, base + active).
  counters[C_LOG_BASE] = counters[C_LOG_TAIL];
  counters[C_LOG_TAIL] = counters[C_LOG_TAIL] + counters[C_ACTIVE_GATED];
  write_dispatch_args(A_ASSIGN, ceil_div(fresh, 64u));
}

// After the block counts are scanned: do the vertices (and the cell list)
// fit? Then the cell list is expanded, and each shard in use gets the range
// of emitting cells that reach it (binary searches over the active entries'
// index ranges, whose offsets increase along the list), its dispatch
// arguments and its draw arguments. Otherwise the expansion and the shards'
// dispatches are empty and the draw arguments keep the previous surface.
// A cell writes its welded vertices in the shard whose vertex range
// [S_BASE, S_VERTEX_END) holds its first index: shard k's indices, the last
// shard in use to the end. The cells of a pool's ghost chunks (and most of
// a skirt chunk's) have no indices (block_mc_common.wgsl): an entry of them
// (index range [o, o)) belongs to the shard whose vertex range holds o, and
// at least one shard is in use whenever the list may hold cells, so each
// such cell runs exactly once.
@group(0) @binding(1) var<storage, read> vertex_offsets: array<u32>;
@group(0) @binding(2) var<storage, read> vertex_counts: array<u32>;
@group(0) @binding(3) var<storage, read> cell_offsets: array<u32>;
@group(0) @binding(4) var<storage, read> cell_counts: array<u32>;
@group(0) @binding(5) var<storage, read_write> shard_info: array<u32>;
@group(0) @binding(6) var<storage, read_write> draw_args: array<u32>;

// First active entry i in [0, n) whose closed index range [offset, offset +
// count] reaches `vertex` or lies past it (offset + count >= vertex): a cell
// without indices has the first index of the cell after it, up to offset +
// count; an entry ending at a shard's base may hold such cells for it.
fn first_reaching(vertex: u32, n: u32) -> u32 {
  var lo = 0u;
  var hi = n;
  while (lo < hi) {
    let mid = lo + (hi - lo) / 2u;
    if (vertex_offsets[mid] + vertex_counts[mid] >= vertex) {
      hi = mid;
    } else {
      lo = mid + 1u;
    }
  }
  return lo;
}

// First active entry i in [0, n) whose index range starts at or after `vertex`.
fn first_starting_at(vertex: u32, n: u32) -> u32 {
  var lo = 0u;
  var hi = n;
  while (lo < hi) {
    let mid = lo + (hi - lo) / 2u;
    if (vertex_offsets[mid] >= vertex) {
      hi = mid;
    } else {
      lo = mid + 1u;
    }
  }
  return lo;
}

@compute @workgroup_size(1)
fn plan_vertices() {
  let total = counters[C_VERTICES];
  var status = counters[C_STATUS];
  if (status == 0u && (total > counters[C_VERTEX_CAPACITY] || counters[C_CELLS] > counters[C_CELL_CAPACITY] ||
                       counters[C_WELDED] > counters[C_WELDED_CAPACITY])) {
    status |= STATUS_VERTEX_OVERFLOW;
    counters[C_STATUS] = status;
  }
  let ok = status == 0u;
  let entries = counters[C_ACTIVE_GATED];
  let cells = counters[C_CELLS];
  write_dispatch_args(A_EXPAND, select(0u, ceil_div(entries, 64u), ok));
  let per_shard = counters[C_PER_SHARD];
  let shards = counters[C_SHARDS];
  // the shards holding indices, at least one (for cells without indices)
  let used = clamp(ceil_div(total, per_shard), 1u, shards);
  for (var k = 0u; k < shards; k++) {
    let r = k * SHARD_STRIDE;
    let base = k * per_shard;
    var first = 0u;
    var count = 0u;
    var vertex_end = base;
    if (ok && k < used) {
      let last = k + 1u == used;
      vertex_end = select(base + per_shard, NONE, last);
      // cells > 0 implies entries > 0; the first entry reaching the shard
      // starts at or before its base (k > 0: base < total)
      if (cells > 0u) {
        let first_entry = first_reaching(base, entries);
        first = cell_offsets[first_entry];
        var end = cells;
        if (!last) {
          // the last entry reaching the shard: the one before the first starting after it
          let last_entry = first_starting_at(base + per_shard, entries) - 1u;
          end = cell_offsets[last_entry] + cell_counts[last_entry];
        }
        count = end - first;
      }
      draw_args[5u * k] = min(total - base, per_shard);
    } else if (ok) {
      draw_args[5u * k] = 0u;
    }
    shard_info[r + S_FIRST] = first;
    shard_info[r + S_COUNT] = count;
    shard_info[r + S_BASE] = base;
    shard_info[r + S_VERTEX_END] = vertex_end;
    let g = dispatch_grid(ceil_div(count, 64u));
    shard_info[r + S_ARGS] = g.x;
    shard_info[r + S_ARGS + 1u] = g.y;
    shard_info[r + S_ARGS + 2u] = g.z;
  }
  if (ok) {
    counters[C_DRAWN_VERTICES] = total;
    counters[C_DRAWN_WELDED] = counters[C_WELDED];
    counters[C_DRAWN_OCCUPIED] = counters[C_OCCUPIED];
  }
}
