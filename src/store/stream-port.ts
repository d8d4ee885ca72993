// The store stream's view of the GPU side (stream/store-stream.ts): what
// it needs of a level's pool (a ChunkedVolume, src/zfp/chunked-volume.ts),
// of a surface over it (an Isosurface), and of the port that makes them
// (gpu-port.ts; tests inject a CPU stand-in), and what it tells its
// listeners.
import type { ChunkIndex, ChunkLevelLayout } from './types.ts';

/** What the stream needs of a ChunkedVolume (src/zfp/chunked-volume.ts). */
export interface LevelVolume {
  readonly poolChunks: number;
  /** GPU bytes the pool holds (slots, page table, parameters). */
  readonly poolBytes: number;
  readonly residentCount: number;
  /** Slots neither holding a chunk nor set aside for one. */
  readonly freeCount: number;
  has(chunk: ChunkIndex): boolean;
  put(chunk: ChunkIndex, bytes: Uint8Array): void;
  evict(chunk: ChunkIndex): void;
  /** Sets the capacity (at least the resident count), resident chunks kept. */
  resize(poolChunks: number): void;
  /** Sets slots aside for these chunks, in this order (others set aside are given back): slots follow the plan, not arrivals. */
  reserve(chunks: readonly ChunkIndex[]): void;
  /** Whether a slot is set aside for this chunk. */
  isReserved(chunk: ChunkIndex): boolean;
  /** The slot of a resident chunk (its blocks' ids start at slot x blocksPerChunk), or undefined. */
  slotOfChunk(chunk: ChunkIndex): number | undefined;
  readonly blocksPerChunk: number;
  destroy(): void;
}
/** What it needs of the surface statistics. */
export interface LevelStats {
  triangles: number;
  cacheBytes: number;
  /** The cache at just the active blocks (no headroom): a cache-only surface's cost per chunk is learnt from it. */
  cacheBytesNeeded?: number;
  vertexBytes: number;
  /** Per-volume buffers outside the surface's cap (the pool, ranges, masks, maps). */
  fixedBytes?: number;
}
/** What it needs of an Isosurface over a LevelVolume. */
export interface LevelSurface<S extends LevelStats = LevelStats> {
  compute(iso: number): Promise<S>;
  /** The cap for cache and vertex buffers (Isosurface.setMemoryBudget). */
  setMemoryBudget(bytes: number): void;
  /** What the cache and vertex buffers hold now (what the cap limits). */
  readonly budgetedBytes: number;
  /** Empties the block cache back to its first size (the drawn mesh stays): memory for another surface. */
  trimCache(): void;
  /** [min, max] per block id (slot x blocksPerChunk + block in chunk): the ranges of a store without range arrays. */
  readBlockRanges?(): Promise<Float32Array>;
  /** [min, max] per listed slot of its chunk's decoded values (Isosurface.readSlotRanges): ranges learnt as chunks arrive. */
  readSlotRanges?(slots: readonly number[]): Promise<Float32Array>;
  /** Draws a copy of the last computed surface from now on (Isosurface.present): a view stream's steps are snapshots. */
  present?(): void;
  /** Bytes the drawn copy holds, and what a present() now would hold. */
  readonly presentedBytes?: number;
  readonly presentBytesNeeded?: number;
  /**
   * Lets go of everything but the drawn copy (a lowered budget, a suspended
   * stream): the copy stays drawable until destroy(); nothing can be
   * computed on the surface any more.
   */
  release?(): void;
  /**
   * A copy of the last computed surface that the caller owns (Isosurface:
   * newCopy + copyInto): the other surfaces of a step (several isovalues
   * drawn from the same resident chunks) are copies made one after another.
   */
  copy?(): SurfaceCopy;
  destroy(): void;
}
/** A copy of a computed surface (SurfaceSnapshot): held until destroyed. */
export interface SurfaceCopy {
  /** Bytes it holds. */
  readonly byteSize: number;
  destroy(): void;
}
/** The GPU side, injected (the real one: gpu-port.ts; tests: a CPU fake). */
export interface StreamGpu<
  V extends LevelVolume = LevelVolume,
  S extends LevelStats = LevelStats,
  F extends LevelSurface<S> = LevelSurface<S>,
> {
  createVolume(layout: ChunkLevelLayout, poolChunks: number): V;
  createSurface(volume: V, memoryBudgetBytes: number): Promise<F>;
  /** Its surfaces hold only their caches (the ray caster's; IsosurfaceOptions.cacheOnly): the cost model guesses no vertices. */
  readonly cacheOnly?: boolean;
  /** GPU bytes held now by everything made here (pools, surfaces and all their buffers): this stream's share of its budget. */
  readonly allocatedBytes: number;
  /** GPU bytes a pool of `poolChunks` chunks of this layout holds. */
  poolBytesFor(layout: ChunkLevelLayout, poolChunks: number): number;
}

export interface StreamProgress {
  iso: number;
  level: number;
  chunksDone: number;
  chunksNeeded: number;
  /** Chunk bytes fetched so far (all levels, this store). */
  bytesFetched: number;
  phase: 'fetching' | 'computing' | 'shown' | 'stopped';
  /** Why refinement stopped above level 0 (phase 'stopped'). */
  reason?: string;
  /** Why it stopped: the memory budget, a chunk that could not be fetched or put, the GPU, or a limit of the level's layout. */
  cause?: 'budget' | 'chunk' | 'gpu' | 'limit';
  /** A stop for a failed chunk: when the refinement will be tried again (ms from now). */
  retryInMs?: number;
}

export interface ShownSurface<V, S extends LevelStats, F extends LevelSurface<S> = LevelSurface<S>> {
  level: number;
  iso: number;
  volume: V;
  surface: F;
  stats: S;
}

/** GPU bytes of the stream now: pools, surfaces (everything else: per-level buffers, cache, vertices, scratch), and both. */
export interface StreamGpuBytes {
  pools: number;
  surfaces: number;
  total: number;
  /** Of the surfaces: cache and vertex buffers (the part the budget's remainder caps). */
  cache: number;
  vertices: number;
}
