// The contract between the isosurface pipeline (src/isosurface/) and its
// users: the page (renderer, stats panel, benchmark), the CLI and the tests.

import type { PassTiming, TimingSource } from '../gpu/timing.ts';
import type { Dims } from '../core/naming.ts';

export interface IsosurfaceOptions {
  /** Cache slots to start with (one slot = one decoded 4x4x4 block, 256 bytes). Default: 10% of the blocks. */
  initialCacheSlots?: number;
  /** Vertices the output buffers hold at first (8 bytes each). Default: chosen from the volume size. */
  initialVertexCapacity?: number;
  /**
   * Bytes the cache (slot data and bookkeeping) and the vertex output may take
   * together. Growth beyond it is refused with an IsosurfaceBudgetError.
   * Default: half of the device's maxBufferSize, at most 2 GiB.
   */
  memoryBudgetBytes?: number;
  /**
   * Only the cache (the ray caster's surface, render/ray-layer.ts): each
   * surface selects its active blocks and decodes them into the cache, and
   * makes no triangles (no classification, no vertex output; the vertex
   * buffers stay at their smallest). Default false.
   */
  cacheOnly?: boolean;
  /** Largest index buffer binding (tests lower it to force several index shards). Default: the device limit. */
  maxVertexBindingBytes?: number;
  /**
   * Added by the pipeline: largest storage binding (default: the device's
   * maxStorageBufferBindingSize; tests lower it). The cache's slot data
   * (256 B per slot) is one binding, so the cache holds at most this / 256
   * slots; a surface with more active blocks is refused with a clear error.
   */
  maxStorageBindingBytes?: number;
  /** Record per-stage GPU times (timestamp queries where present). Default true. */
  timing?: boolean;
  /**
   * Added by the pipeline: grid limit per dispatch dimension (default: the
   * device's). Tests lower it so small dispatches use 2D/3D grids.
   */
  maxWorkgroupsPerDimension?: number;
  /**
   * Added by the pipeline: edge, in blocks, of the groups of the hierarchical
   * active-block selection (groups first, then the blocks of active groups).
   * Default 4 (16^3 voxels); a chunked store uses its chunk (64^3 voxels: 16).
   */
  groupEdgeBlocks?: number;
  /**
   * Added by the pipeline: computations submitted and not yet read back at
   * once (scrubbing records the next surface without waiting for the
   * previous statistics). Default 2.
   */
  maxSurfacesInFlight?: number;
  /**
   * Kernel family of the zfp block-list decode (the cache fill): 'auto'
   * (default) picks per adapter like the primitives (choosePath); tests force
   * 'emulator' or 'gpu'.
   */
  zfpDecoderPath?: 'auto' | 'emulator' | 'gpu';
  /**
   * Kernel family of the scans and compactions (src/primitives/README.md), and
   * of the zfp decode unless zfpDecoderPath says otherwise: 'auto' (default)
   * picks per adapter; tests force 'gpu' to run the GPU-shaped kernels through
   * the whole pipeline on SwiftShader.
   */
  primitivePath?: 'auto' | 'emulator' | 'gpu';
}

export interface VolumeInfo {
  dims: Dims;
  /** Blocks per axis: ceil(dims / 4). */
  blockGrid: Dims;
  blockCount: number;
  /** Smallest and largest decoded value (from the per-block ranges). */
  valueRange: [number, number];
}

/** Everything the stats panel and the benchmark need about one computed surface. */
export interface IsosurfaceStats {
  isovalue: number;
  activeBlocks: number;
  /** Blocks decompressed into the cache for this surface. */
  newBlocks: number;
  /** Active blocks with triangles. */
  occupiedBlocks: number;
  /** 1 - newBlocks / activeBlocks (1 when nothing is active). */
  hitRate: number;
  /**
   * Welded vertices: one per cut grid edge (VTK's merged point count). Over a
   * chunk pool with roles (ChunkedVolume.setRoles) it includes the vertices
   * owned by ghost chunks' cells on their lower faces, some of which no
   * drawn triangle uses.
   */
  vertices: number;
  /** Triangle corners: indices into the vertices, 3 per triangle (of drawn chunks only, over a pool with roles). */
  indices: number;
  triangles: number;
  cacheSlots: number;
  /** Slots holding a block (valid data), after this update. */
  cacheSlotsUsed: number;
  /** Bytes of the slot data and cache bookkeeping buffers. */
  cacheBytes: number;
  /** What the cache would take at just the active blocks' slots (cacheBytes less the headroom it grew into). */
  cacheBytesNeeded: number;
  /** Bytes of the vertex output buffers (capacity). */
  vertexBytes: number;
  /** Sum of the stages' GPU time, ms. */
  gpuMs: number;
  stages: PassTiming[];
  timingSource: TimingSource;
  /** True if this surface needed the cache or vertex buffers to grow (and was recomputed). */
  grew: boolean;
  /**
   * Added by the pipeline: bytes held per volume outside the budget (the
   * compressed stream, block ranges, active-block mask/offsets/list, scan scratch).
   */
  fixedBytes?: number;
}

/** A surface read back as an indexed mesh (CLI, PLY export). */
export interface SurfaceMesh {
  /** Per welded vertex 3 u32: packed position, block id, normal (IsosurfaceDrawData.vertices). */
  vertices: Uint32Array;
  /** 3 indices into `vertices` per triangle. */
  indices: Uint32Array;
  /** The volume's voxels per axis: how the vertices' block field is laid out (meshPositions in vertex-format.ts decodes it). */
  dims: readonly [number, number, number];
}

/** An index shard: part of the triangles, as indices into the welded vertices, in one buffer (one storage binding). */
export interface IndexShard {
  /** u32 indices into IsosurfaceDrawData.vertices, 3 per triangle. Usage includes INDEX and STORAGE. */
  indices: GPUBuffer;
  /** drawIndexedIndirect arguments [indexCount, instanceCount, firstIndex, baseVertex, firstInstance], written by the GPU. */
  drawArgs: GPUBuffer;
  drawArgsOffset: number;
}

/** What the renderer binds to draw the current surface (and shade it from the volume). */
export interface IsosurfaceDrawData {
  /**
   * The welded vertices, 12 bytes each: u32 packed position (10 bits per
   * axis, x in bits 0-9, y 10-19, z 20-29; local = q * 4 / 1023 voxels from
   * the block origin), u32 block id (raster order, x fastest), u32 normal
   * (octahedral: decode_vertex_normal in vertex_format.wgsl; 0 = none), the
   * volume gradient computed once per surface. Usage includes VERTEX and STORAGE.
   */
  vertices: GPUBuffer;
  shards: IndexShard[];
  info: VolumeInfo;
  /** Decoded blocks, 64 f32 per slot (voxel x + 4y + 16z); valid for every active block of the drawn surface. */
  slotData: GPUBuffer;
  /**
   * Per block: its slot, or 0xffffffff when not cached. (After a refused
   * growth the previous surface stays drawn while the cache may already have
   * moved on: treat 0xffffffff as "no data" when shading.)
   */
  blockToSlot: GPUBuffer;
  /**
   * Per block, [min, max] over its 27-block neighbourhood (2 f32): a block is
   * active at iso when min < iso <= max (the ray caster skips the others). A
   * pipeline's own draw data has it; copies do not.
   */
  neighbourhoodRanges?: GPUBuffer;
  /** Increases whenever any buffer above is replaced (after growth): re-create bind groups then. */
  version: number;
}

export class IsosurfaceBudgetError extends Error {
  constructor(
    message: string,
    readonly neededBytes: number,
    readonly budgetBytes: number,
  ) {
    super(message);
    this.name = 'IsosurfaceBudgetError';
  }
}

/**
 * Added by the pipeline: `compute(iso)` rejects with this when a newer
 * isovalue replaced `iso` before it was computed (newest wins).
 */
export class IsosurfaceSupersededError extends Error {
  constructor(
    readonly isovalue: number,
    readonly replacedBy: number,
  ) {
    super(`the surface at iso ${isovalue} was not computed: iso ${replacedBy} replaced it`);
    this.name = 'IsosurfaceSupersededError';
  }
}

/**
 * Added by the pipeline: a computation failed on the GPU (a validation error
 * or out of memory in its submission). Nothing of it ran; the previous
 * surface stays drawn.
 */
export class IsosurfaceGpuError extends Error {
  constructor(
    message: string,
    readonly isovalue: number,
  ) {
    super(`Isosurface: ${message}`);
    this.name = 'IsosurfaceGpuError';
  }
}

/** Share of a surface's active blocks that were already cached (1 when none are active). */
export function hitRate(active: number, fresh: number): number {
  return active === 0 ? 1 : 1 - fresh / active;
}
