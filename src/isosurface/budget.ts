// Memory accounting and growth policy of the cache and the vertex output,
// shared by the Isosurface and the CPU model of the cache (lru-model.ts), so
// both grow to the same capacities.
import { CACHE_BYTES_PER_SLOT } from './lru-cache.ts';
import { cellBytesFor, MC_BYTES_PER_SLOT } from './block-mc.ts';
import { logBytesFor, SLOT_BYTES } from './layout.ts';
import { SurfaceOutput } from './vertex-output.ts';

/**
 * Bytes the cache takes at `slots` slots: slot data, maps, the LRU log,
 * per-active buffers (the classification's, unless the surface is cache
 * only: IsosurfaceOptions.cacheOnly), blockToSlot.
 */
export function cacheBytesFor(slots: number, blockCount: number, cacheOnly = false): number {
  return slots * (CACHE_BYTES_PER_SLOT + (cacheOnly ? 0 : MC_BYTES_PER_SLOT)) + logBytesFor(slots) + blockCount * 4;
}

/**
 * Bytes the surface output takes at `indices` triangle corners and `welded`
 * vertices: the index shards, the vertex buffer and the emitting-cell list.
 */
export function vertexBytesFor(indices: number, welded: number, perShard: number): number {
  return SurfaceOutput.bytesFor(indices, welded, perShard) + cellBytesFor(indices);
}

/**
 * Welded vertices to allocate with `indices` triangle corners: a closed
 * surface has about one vertex per 6 corners, open pieces and small
 * components more, so a quarter (a surface needing more grows them).
 */
export function weldedFor(indices: number): number {
  return Math.max(1, Math.ceil(indices / 4));
}

/**
 * Capacity after growth when `needed` exceeds `current`: 1.5x the current
 * capacity (fewer regrowths on the way up), at least `needed`, at most `max`
 * (the block count for the cache); never below `needed`.
 */
export function grownCapacity(current: number, needed: number, max = Infinity): number {
  return Math.max(needed, Math.min(max, Math.ceil(current * 1.5)));
}

/** Default memory budget: half of maxBufferSize, at most 2 GiB (types.ts). */
export function defaultMemoryBudget(limits: GPUSupportedLimits): number {
  return Math.min(limits.maxBufferSize / 2, 2 ** 31);
}

export function formatMB(bytes: number): string {
  return `${(bytes / 2 ** 20).toFixed(bytes < 10 * 2 ** 20 ? 2 : 1)} MB`;
}

/**
 * Most cache slots on a device: the slot data (256 B per slot) is bound
 * whole by the decoder, classification and vertex passes, so it must fit one
 * storage binding (and one buffer). The other per-slot buffers are 64 B per
 * slot or less. At most 2^25 slots.
 */
export function maxCacheSlots(limits: GPUSupportedLimits, maxStorageBindingBytes = Infinity): number {
  const bytes = Math.min(maxStorageBindingBytes, limits.maxStorageBufferBindingSize, limits.maxBufferSize);
  const slots = Math.floor(bytes / SLOT_BYTES);
  if (slots < 1) throw new RangeError(`maxStorageBindingBytes must hold at least one cache slot (${SLOT_BYTES} bytes)`);
  // An emitting-cell record keeps its active entry (< slots) in bits 6-30,
  // bit 31 being CELL_NO_INDICES (block_expand.wgsl): 8 GiB of slot data.
  return Math.min(slots, 2 ** 25);
}
