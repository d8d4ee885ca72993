// What an Isosurface reads its blocks from: one zfp stream (ZfpGpuStream,
// every block present from load) or a chunked source (src/store's
// ChunkedVolume: a pool of compressed chunks, some resident). The pipeline is
// the same; a chunked source brings its own block addressing for the decoder
// and keeps the block ranges, neighbourhood ranges and group ranges of the
// chunks that changed up to date (encodeSync, before each surface).
import type { ZfpBlockSource } from '../zfp/decoder.ts';
import type { ZfpGpuStream } from '../zfp/gpu-stream.ts';

/** The buffers of an Isosurface a chunked source updates before a surface. */
export interface ChunkSyncTargets {
  /** 2 f32 per block. */
  blockRanges: GPUBuffer;
  neighbourhoodRanges: GPUBuffer;
  /** 2 f32 per group (= chunk). */
  groupRanges: GPUBuffer;
  blockToSlot: GPUBuffer;
  slotToBlock: GPUBuffer;
  slotAge: GPUBuffer;
  counters: GPUBuffer;
}

export interface ChunkedBlockSource {
  readonly kind: 'chunked';
  readonly info: { readonly fileName: string; readonly dims: [number, number, number]; readonly blockGrid: [number, number, number]; readonly blockCount: number };
  /** Chunk edge / 4: the groups of the hierarchical selection are the chunks. */
  readonly groupEdgeBlocks: number;
  /** GPU bytes the source holds (pool, page table, ...), fixed. */
  readonly poolBytes: number;
  /** The decoder's view of the pool. */
  readonly blocks: ZfpBlockSource;
  /** Called once by the Isosurface that reads it (a source serves one); every resident chunk counts as changed. */
  attach(): void;
  /** Records the update of the chunks changed since the last call (nothing if none); cost follows the chunks changed. */
  encodeSync(encoder: GPUCommandEncoder, targets: ChunkSyncTargets): void;
  /** Resident chunks now. */
  readonly residentCount: number;
}

export type IsosurfaceSource = ZfpGpuStream | ChunkedBlockSource;

export function isChunked(source: IsosurfaceSource): source is ChunkedBlockSource {
  return (source as ChunkedBlockSource).kind === 'chunked';
}
