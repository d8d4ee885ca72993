// What opening a store gives (openStore, open-store.ts): its levels and how
// to read them, the same for zfp stores and stores of lossless chunks
// (open-source.ts); and what opening takes.
import type { AsyncReadable, GetOptions } from '@zarrita/storage';
import type { ChunkIndex, ChunkLevelLayout } from '../types.ts';
import type { RetryCounters, RetryPolicy } from './retrying-store.ts';
import type { RateSample, SourceInfo } from './source-store.ts';
import type { StoreMeter } from './stores.ts';

export interface StoreLevel {
  /** 0 = finest. */
  index: number;
  /** The array's path in the store ("0", "1", ...; "" for a store that is one array). */
  path: string;
  layout: ChunkLevelLayout;
  /** Inner chunks per shard edge, 1 when unsharded. */
  shardChunks: number;
  chunkCount: number;
  /** chunkCount x chunkBytes: what fetching the whole level costs. */
  storedBytes: number;
  /** Path of the per-chunk [min, max] array, or null (ranges come from the GPU as chunks arrive). */
  rangesPath: string | null;
  /** Leading axes (OME t, c; chunks of 1 along each) dropped from the array's shape. */
  leadingAxes: number;
  /** The index read along each leading axis (the time point shown on t; 0 on axes of length 1); zeros when absent. */
  leadingIndex?: number[];
  /** Why this level cannot be shown (a limit it exceeds), or null. */
  unusable: string | null;
}

/** A store's t axis: index `index` of `count`; its physical time is origin + index * step (in `unit`) when step is known. */
export interface StoreTimeAxis {
  index: number;
  count: number;
  /** OME scale along t (level 0), or null when the metadata give none. */
  step: number | null;
  /** OME translation along t (level 0), 0 when none. */
  origin: number;
  unit: string | null;
}

/** The physical time of a time point, or null when the store's metadata give no step. */
export function timeValueOf(axis: StoreTimeAxis, index: number): number | null {
  return axis.step === null ? null : axis.origin + index * axis.step;
}

export interface ZfpStore {
  name: string;
  levels: StoreLevel[];
  /** x, y, z of level 0 (1, 1, 1 when the store does not say). */
  voxelSize: [number, number, number];
  /** Per level, where its voxel 0 sits in level-0 voxels (OME translation; metadata.ts levelOffsetsOf). */
  levelOffsets: [number, number, number][];
  /**
   * Per level, how many level-0 voxels one of its voxels spans on x, y and z
   * (2^L on every axis unless the store's OME scales say otherwise: a level
   * may halve only some axes; metadata.ts pyramidChain).
   */
  levelScales: [number, number, number][];
  unit: string | null;
  /** The store's time axis (absent when it has none): the time point shown, of how many, and where the OME metadata put it. */
  time?: StoreTimeAxis;
  /** Decoded level-0 [min, max] from our attributes, else null. */
  valueRange: [number, number] | null;
  /** Things a user should know (an unfinished store, no range arrays). */
  notes: string[];
  /** A store of lossless chunks (compressed on the GPU as bricks arrive): its format, codecs, type, axes, rate; null for zfp stores. */
  source: SourceInfo | null;
  /** Every byte and request through the store (metadata included; every try of a retried request counts). */
  meter: StoreMeter;
  /** Tries after failures, requests that failed for good, faults seen (retrying-store.ts). */
  retries: RetryCounters;
  /** Bytes read while opening (metadata). */
  metadataBytes: number;
  /** The chunk's stored bytes, checked (an absent chunk: the fill value's stream); rejects with StoreError (or an AbortError). */
  readChunk(level: number, chunk: ChunkIndex, options?: GetOptions): Promise<Uint8Array>;
  /** Stops what the store runs for its reads (decode workers); reads after it fail. */
  close?(): void;
  /** Whether readChunk's bytes stand for a chunk absent from the store (nothing was transferred for them). */
  isAbsent(bytes: Uint8Array): boolean;
  /** A store of lossless chunks: [min, max] of the source values (as float32) of the level's bricks read so far, or null. */
  sourceValueRange?(level: number): [number, number] | null;
  /** A store of lossless chunks: source chunks decoded, their decoded bytes and the CPU time it took (ms, fetch waits included). */
  sourceDecode?(): { chunks: number; bytes: number; ms: number; nonFinite: number };
  /** Bricks in the page's decode workers now, and the most there were at once (a store read in Web Workers). */
  decodeQueue?(): { queued: number; maxQueued: number };
  /** [min, max] per chunk (chunk index order), or null when the store has no range arrays. */
  readRanges(level: number, options?: GetOptions): Promise<Float32Array | null>;
}

export interface OpenStoreOptions {
  /** How requests are tried again (retrying-store.ts; tests shorten the waits). */
  retry?: RetryPolicy;
  /** Stores of lossless chunks: the GPU's zfp rate for their bricks (default DEFAULT_SOURCE_RATE, 8). zfp stores keep their own. */
  rate?: number;
  /** Stores with a time or channel axis: which one is shown (default 0). */
  time?: number;
  channel?: number;
  /**
   * Stores of lossless chunks with no rate given (nor a ranges sidecar's):
   * chooses the rate from a sample of the coarsest level's bricks (values of
   * `dtype`, dims x, y, z; src/store/rate.ts does it on the GPU). Without
   * it, DEFAULT_SOURCE_RATE.
   */
  chooseRate?: (sample: RateSample) => Promise<{ rate: number; description: string }>;
  /** Stores of lossless chunks: decode in Web Workers (true: as many as the machine suggests), where they exist (the page). */
  decodeWorkers?: boolean | number;
  /** Stores of lossless chunks: per-brick ranges written apart (ranges-sidecar.ts), `name` for messages. */
  ranges?: { store: AsyncReadable; name: string };
  /** Stores of lossless chunks: CPU bytes of decoded source chunks kept while neighbouring bricks need them (default 256 MiB). */
  sourceCacheBytes?: number;
}
