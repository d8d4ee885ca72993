// Shared by the isosurface kernels: the volume parameters (a uniform) and the
// layout of the counters buffer (u32 words written and read on the GPU only;
// src/isosurface/layout.ts mirrors these numbers and a test checks them).
// Needs shaders/common/grid.wgsl (dispatch grids).

// "No slot" / "no block" in blockToSlot, slotToBlock and the LRU log.
const NONE: u32 = 0xffffffffu;

// Roles of a pool's chunks (ChunkedVolume.setRoles, CHUNK_ROLE_CODES), from
// the top 2 bits of their slot-table words (block_role, group_role in
// blocks_pool.wgsl); a whole stream's blocks are all drawn (blocks_stream.wgsl).
const ROLE_DRAWN: u32 = 0u;  // its cells make triangles
const ROLE_GHOST: u32 = 1u;  // lends its voxels to drawn chunks: active, no triangles
const ROLE_IDLE: u32 = 2u;   // resident but unused: never active, never read
// A ghost whose cells of chunk-local coordinate 0 on an axis whose chunk
// below is drawn make triangles too (skirt_axes in blocks_*.wgsl). An empty
// slot's word (NONE) also reads as 3: only occupied slots are asked.
const ROLE_SKIRT: u32 = 3u;

// Flag of an emitting-cell record (expand_cells): the cell writes the
// vertices it owns but no index (block_mc_common.wgsl).
const CELL_NO_INDICES: u32 = 0x80000000u;

// Words of the counters buffer. 0-7 are written by the host (at creation and
// after growth), the rest by the kernels and primitives of one computation.
const C_BLOCKS: u32 = 0u;          // blocks in the volume
const C_SLOTS: u32 = 1u;           // cache slots (capacity)
const C_VERTEX_CAPACITY: u32 = 2u; // triangle corners (indices) the shards hold together
const C_SHARDS: u32 = 3u;          // vertex shards
const C_PER_SHARD: u32 = 4u;       // vertices per full shard
const C_CELL_CAPACITY: u32 = 5u;   // entries of the emitting-cell list
const C_GROUPS: u32 = 6u;          // groups of blocks (active_groups.wgsl)
const C_GROUP_SIZE: u32 = 7u;      // blocks per group (edge^3)
const C_ACTIVE: u32 = 8u;          // active blocks (scan total)
const C_ACTIVE_GATED: u32 = 9u;    // active blocks, or 0 when the cache is too small
const C_SLOTS_GATED: u32 = 10u;    // slots, or 0 when the cache is too small
const C_NEW: u32 = 11u;            // active blocks not cached (scan total)
const C_LOG_COMPACT: u32 = 12u;    // LRU log entries to compact: the tail when the log is full, else 0
const C_LOG_VALID: u32 = 13u;      // valid entries kept by a log compaction (scan total)
const C_VERTICES: u32 = 14u;       // triangle corners (indices) of the surface (scan total)
const C_OCCUPIED: u32 = 15u;       // active blocks that emit triangles (counted by classify_blocks)
const C_STATUS: u32 = 16u;         // STATUS_* bits of this computation
const C_SLOTS_USED: u32 = 17u;     // slots holding a block (kept across computations)
const C_DRAWN_VERTICES: u32 = 18u; // vertices in the draw arguments now
const C_DRAWN_OCCUPIED: u32 = 19u; // occupied blocks of the drawn surface
const C_COMPACT_NEW: u32 = 20u;    // active entries to compact into the new list: active gated, or 0 when nothing is new
const C_CELLS: u32 = 21u;          // emitting cells (scan total)
const C_ACTIVE_GROUPS: u32 = 22u;  // active groups of blocks (scan total)
const C_GROUP_BLOCKS: u32 = 23u;   // blocks of the active groups: active groups x blocks per group
// (Words 24-43: indirect arguments below.)
const C_REQUEST: u32 = 44u;        // host-written id of the submission; its statistics carry it (no stale counters)
const C_LOG_SIZE: u32 = 45u;       // positions of the LRU log (a power of two >= 2 x slots; host)
const C_LOG_TAIL: u32 = 46u;       // next free position of the LRU log
const C_LOG_BASE: u32 = 47u;       // where this computation appends its active slots (plan_update)
const C_WELDED: u32 = 48u;          // welded vertices of the surface (scan total; C_VERTICES counts triangle corners)
const C_WELDED_CAPACITY: u32 = 49u; // welded vertices the vertex buffer holds (host)
const C_DRAWN_WELDED: u32 = 50u;    // welded vertices of the drawn surface
// Indirect dispatch arguments (x, y, z), written by the plan kernels.
const A_SLOTS: u32 = 24u;   // rebuild_log after a log compaction: ceil(2 x log size / 64), or 0
const A_MARK: u32 = 28u;    // mark_cached, append_active, classify_blocks: ceil(active gated / 64)
const A_ASSIGN: u32 = 32u;  // pick_victims_of_new, assign_slots: ceil(new / 64)
const A_EXPAND: u32 = 36u;  // expand_cells: ceil(active gated / 64), or 0 when the surface does not fit
const A_GROUP_BLOCKS: u32 = 40u;  // mark_group_blocks, compact_block_ids: ceil(group blocks / 64)

const STATUS_CACHE_SHORTFALL: u32 = 1u;  // more active blocks than slots: nothing was assigned or meshed
const STATUS_VERTEX_OVERFLOW: u32 = 2u;  // more vertices than capacity: nothing was written, draw args kept

// Vertex shard records (shard_info), 64 words (256 bytes) apart.
const S_FIRST: u32 = 0u;      // first entry of the cell list whose vertices reach this shard
const S_COUNT: u32 = 1u;      // cell-list entries to process for this shard
const S_BASE: u32 = 2u;       // global index of the shard's first vertex
const S_VERTEX_END: u32 = 3u; // cells whose first index is in [S_BASE, S_VERTEX_END) write their welded vertices here
const S_ARGS: u32 = 4u;       // dispatch arguments (x, y, z) of the vertex pass for this shard
const SHARD_STRIDE: u32 = 64u;

struct VolumeParams {
  dims: vec3u,
  block_count: u32,
  grid: vec3u,   // blocks per axis
  iso: f32,      // the isovalue (float32), rewritten before each computation
}

fn block_coords_of(b: u32, grid: vec3u) -> vec3u {
  return vec3u(b % grid.x, (b / grid.x) % grid.y, b / (grid.x * grid.y));
}

fn block_index_of(c: vec3u, grid: vec3u) -> u32 {
  return c.x + grid.x * (c.y + grid.y * c.z);
}

// Words per region of the block counts and their offsets (block_classify.wgsl,
// block_expand.wgsl): the cache slots rounded up to 64, so each region starts
// at a multiple of 256 bytes (a storage binding's offset alignment).
fn count_stride(slots: u32) -> u32 {
  return (slots + 63u) & ~63u;
}
