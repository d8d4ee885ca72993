// Numbers shared with the WGSL kernels (shaders/isosurface/common.wgsl holds
// the same constants; tests/unit/isosurface/vertex-format.test.ts checks they agree).

/** "No slot" in blockToSlot, "no block" in slotToBlock and the LRU log. */
export const NONE = 0xffffffff;

/** Word indices in the counters buffer (see common.wgsl for what each holds). */
export const C = {
  blocks: 0,
  slots: 1,
  vertexCapacity: 2,
  shards: 3,
  perShard: 4,
  cellCapacity: 5,
  groups: 6,
  groupSize: 7,
  active: 8,
  activeGated: 9,
  slotsGated: 10,
  new: 11,
  logCompact: 12,
  logValid: 13,
  vertices: 14,
  occupied: 15,
  status: 16,
  slotsUsed: 17,
  drawnVertices: 18,
  drawnOccupied: 19,
  compactNew: 20,
  cells: 21,
  activeGroups: 22,
  groupBlocks: 23,
  /** Host-written id of the submission (its statistics are checked against it). */
  request: 44,
  /** Positions of the LRU log (host), its tail, and where a computation appends (lru.wgsl). */
  logSize: 45,
  logTail: 46,
  logBase: 47,
  /** Welded vertices of the surface (scan total), their capacity (host), those of the drawn surface. */
  welded: 48,
  weldedCapacity: 49,
  drawnWelded: 50,
} as const;

/** Word offsets of indirect dispatch arguments (x, y, z) in the counters buffer. */
export const A = {
  slots: 24,
  mark: 28,
  assign: 32,
  expand: 36,
  groupBlocks: 40,
} as const;

export const STATUS_CACHE_SHORTFALL = 1;
export const STATUS_VERTEX_OVERFLOW = 2;

/** The counters buffer: 64 words. */
export const COUNTER_WORDS = 64;
export const COUNTERS_BYTES = COUNTER_WORDS * 4;

/** Default edge, in blocks, of the groups of the active-block selection (16^3 voxels). */
export const DEFAULT_GROUP_EDGE_BLOCKS = 4;

/** Vertex shard records in shard_info: 64 words apart (a storage offset alignment). */
export const SHARD_RECORD_BYTES = 256;
export const S = { first: 0, count: 1, base: 2, vertexEnd: 3, args: 4 } as const;
/** Bytes of one shard record bound by the vertex pass. */
export const SHARD_RECORD_BINDING = 32;
/** drawIndexedIndirect arguments per index shard: [indexCount, instanceCount, firstIndex, baseVertex, firstInstance]. */
export const DRAW_ARGS_BYTES = 20;

/** Bytes of one decoded block in the slot data (64 f32). */
export const SLOT_BYTES = 256;
/** Bytes of one welded vertex: the compressed position (8 bytes) and its octahedral normal (vertex_format.wgsl). */
export const VERTEX_BYTES = 12;
/** Bytes of one index (a triangle corner). */
export const INDEX_BYTES = 4;
/** Bytes of one entry of the emitting-cell list: (entry << 6 | cell, bit 31 CELL_NO_INDICES in common.wgsl) and its first index. */
export const CELL_RECORD_BYTES = 8;

/** Positions of the LRU log for `slots` slots: a power of two >= 2 x slots (at least 64). */
export function logSizeFor(slots: number): number {
  let p = 64;
  while (p < 2 * slots) p *= 2;
  return p;
}

/** Words of the LRU log's 16-ary count tree over `logSize` positions (lru.wgsl: levels of max(1, P >> 4k) nodes up to a single one). */
export function logTreeWords(logSize: number): number {
  let words = 0;
  for (let k = 1; ; k++) {
    const nodes = Math.max(1, Math.floor(logSize / 16 ** k));
    words += nodes;
    if (nodes === 1) return words;
  }
}

/** Bytes of the LRU log at `slots` slots: log, valid flags, scan offsets, compaction scratch (4 B per position each) and the count tree. */
export function logBytesFor(slots: number): number {
  const p = logSizeFor(slots);
  return p * 16 + logTreeWords(p) * 4;
}

/**
 * The uniform VolumeParams (common.wgsl): dims (3 u32), block count, block
 * grid (3 u32), the isovalue (f32, rewritten before each surface).
 */
export const VOLUME_PARAMS = { bytes: 32, isoOffset: 28 } as const;
