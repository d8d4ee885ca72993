// One opened store, as the page and the CLI both use it: the store (its
// requests metered), the chunk fetcher, the GPU port, the stream (level by
// level, or refined by the view), the chunks that came over (a bit per
// chunk), the record, and close(). Opening is all or nothing: an open that
// fails part-way (or that the caller abandons with close()) lets its store
// go, decode workers and requests included, and frees what the stream made.
import type { AsyncReadable } from '@zarrita/storage';
import type { GpuContext } from '../gpu/device.ts';
import type { Isosurface } from '../isosurface/isosurface.ts';
import type { IsosurfaceStats } from '../isosurface/types.ts';
import type { ChunkedVolume } from '../zfp/chunked-volume.ts';
import { ChunkFetcher } from './fetch/chunk-fetcher.ts';
import { GpuBudget } from '../gpu/budget.ts';
import { type ChunkedStreamGpu, chunkedGpu, storeEncoder } from './gpu-port.ts';
import { CutPlanner } from './stream/cut-planner.ts';
import { LevelPlanner } from './stream/level-planner.ts';
import type { LearntRanges } from './learnt-ranges.ts';
import type { StreamGpuBytes } from './stream-port.ts';
import { type ViewSpec, StoreStream } from './stream/store-stream.ts';
import type { ChunkStoreStream } from './gpu-port.ts';
import { openStore } from './zarr/open-store.ts';
import type { SourceInfo } from './zarr/source-store.ts';
import type { OpenStoreOptions, ZfpStore } from './zarr/store.ts';
import { MeteredStore } from './zarr/stores.ts';
import { FetchedChunks } from './fetched-chunks.ts';

export { FetchedChunks };
import type { PreparedTime } from './series/prefetch.ts';

/** What a store session's figures say (the CLI's `store` record; the page's panel reads the same counters). */
export interface StoreRecord {
  store: string;
  level: number;
  levels: number;
  dims: [number, number, number];
  chunkEdge: number;
  rate: number;
  /** Distinct chunks (bricks, for a store of lossless chunks) put at the level / chunks of the level. */
  chunks: number;
  levelChunks: number;
  /** A store of lossless chunks: format, codecs, type, axes, rate (null for zfp stores). */
  source: SourceInfo | null;
  /** A store of lossless chunks: [min, max] of the source values of the level's bricks read (all of it once the level was read whole). */
  sourceValueRange: [number, number] | null;
  /** A store of lossless chunks: source chunks decoded (count, decoded bytes, ms from request to decoded, summed over chunks). */
  sourceDecode: { chunks: number; bytes: number; ms: number; nonFinite: number } | null;
  /** Level 0's voxel size (x, y, z) and unit, from the store's metadata. */
  voxelSize: [number, number, number];
  unit: string | null;
  /** Bytes through the store: chunk bytes, and everything (metadata, range arrays, shard indexes). */
  chunkBytesFetched: number;
  bytesFetched: number;
  metadataBytes: number;
  requests: number;
  /** Every chunk of every level (what a full download would be). */
  storeChunkBytes: number;
  /** GPU memory budget of the stream: everything it holds on the GPU. */
  budgetBytes: number;
  /** GPU bytes held now, counted where they are made (pools, the surface's per-level buffers, cache, vertices, scratch). */
  gpuBytes: number;
  /** Of gpuBytes: the pool of compressed chunks, and the surface's cache and vertex buffers. */
  gpuPoolBytes: number;
  gpuCacheBytes: number;
  gpuVertexBytes: number;
  /** The most GPU bytes held at once so far. */
  gpuPeakBytes: number;
  /** Chunks a surface needed by their ranges that a clip (--clip, --plane) left out: neither fetched nor drawn. */
  clippedChunks: number;
  /** Requests tried again after a transient failure, requests that failed for good, and what the failed tries saw. */
  retries: number;
  failedRequests: number;
  faults: Record<string, number>;
}

export interface StoreSessionOptions {
  /** How the store is opened (rate, time point, channel, ranges sidecar, retries, decode workers). */
  open: OpenStoreOptions;
  /**
   * The GPU memory the stream holds against: a budget shared with the rest
   * of the page (gpu/budget.ts), or bytes for a budget of its own (the CLI).
   */
  budget: GpuBudget | number;
  /** Requests in flight at once (default 8). */
  maxInFlight?: number;
  /** Ranges learnt earlier for this store (the page keeps them per opened source). */
  learnt?: (store: ZfpStore) => LearntRanges | undefined;
  /**
   * Refined by the view: the first view, given the opened store; null (or
   * absent) streams level by level. May throw (a view that does not fit the
   * store): the open then fails and lets the store go.
   */
  view?: (store: ZfpStore) => ViewSpec | null;
  /** Surfaces hold only their block caches, no triangles (drawn by rays: render/ray-layer.ts); default false. */
  cacheOnly?: boolean;
  /**
   * A time point made ready ahead (series/prefetch.ts): its store (opened
   * with these options at that time point), metered source, fetcher with
   * what it fetched and the chunks counted are taken over; `open` is not
   * read again.
   */
  prepared?: PreparedTime;
  /** Called with the stream as soon as it is made, before its first view (the CLI turns off retries and snapshots here, and sets skirts). */
  setup?: (stream: ChunkStoreStream) => void;
}

export class StoreSession {
  #closed = false;

  private constructor(
    /** The store's name in messages (a URL or a path). */
    readonly name: string,
    readonly store: ZfpStore,
    readonly metered: MeteredStore,
    readonly fetcher: ChunkFetcher,
    readonly port: ChunkedStreamGpu,
    /** The stream (one engine, planned by the view or level by level). */
    readonly stream: ChunkStoreStream,
    /** The chunks that came over (counted once). */
    readonly fetched: FetchedChunks,
  ) {}

  /** The GPU memory the stream holds against (shared with the page's other users of it). */
  get budget(): GpuBudget {
    return this.stream.budget;
  }

  /** The budget's limit, bytes. */
  get budgetBytes(): number {
    return this.stream.budget.bytes;
  }

  /**
   * Stops streaming and keeps only the copies of the step on screen
   * (StoreStream.suspend): the page opens another store within the same
   * budget while this one stays drawn. A new isovalue resumes it (the new
   * store failed to open); close() ends it (the new one is on screen).
   */
  suspend(): void {
    if (!this.#closed) this.stream.suspend();
  }

  /** Ends the store: no more requests, decode workers end, everything on the GPU is given back. */
  close(): void {
    if (this.#closed) return;
    this.#closed = true;
    this.stream.destroy();
    this.fetcher.cancelAll();
    this.store.close?.();
  }

  /**
   * The record: `level` the level streamed (or the finest a view drew),
   * `layoutLevel` whose dims, chunks and rate it gives, `chunksOf` the level
   * whose chunks it counts (all levels when absent).
   */
  record(level: number, layoutLevel: number, chunksOf?: number): StoreRecord {
    const { store, metered } = this;
    const lv = store.levels[layoutLevel];
    const gpu: StreamGpuBytes = this.stream.gpuBytes;
    return {
      store: this.name,
      level,
      levels: store.levels.length,
      dims: lv.layout.dims,
      chunkEdge: lv.layout.chunkEdge,
      rate: lv.layout.rate,
      chunks: this.fetched.chunks(chunksOf),
      source: store.source,
      sourceValueRange: store.sourceValueRange?.(layoutLevel) ?? null,
      sourceDecode: store.sourceDecode?.() ?? null,
      voxelSize: store.voxelSize,
      unit: store.unit,
      levelChunks: lv.chunkCount,
      // a store of lossless chunks: what came over for the bricks (their source chunks), not the bricks' values
      chunkBytesFetched: store.source ? metered.meter.bytes - store.metadataBytes : this.fetched.bytes(chunksOf),
      bytesFetched: metered.meter.bytes,
      metadataBytes: store.metadataBytes,
      requests: metered.meter.requests,
      storeChunkBytes: store.levels.reduce((a, l) => a + l.storedBytes, 0),
      budgetBytes: this.stream.budgetBytes,
      gpuBytes: gpu.total,
      gpuPoolBytes: gpu.pools,
      gpuCacheBytes: gpu.cache,
      gpuVertexBytes: gpu.vertices,
      gpuPeakBytes: this.port.meter.peak,
      clippedChunks: this.stream.clippedChunks,
      retries: store.retries.retries,
      failedRequests: store.retries.failed,
      faults: { ...store.retries.faults },
    };
  }

  /**
   * Opens `source` (named `name` in messages) and its stream on `gpu`. The
   * refined stream has planned its first view when this resolves; nothing
   * has been fetched for a surface yet.
   */
  static async open(gpu: GpuContext, source: AsyncReadable, name: string, options: StoreSessionOptions): Promise<StoreSession> {
    const prepared = options.prepared;
    const metered = prepared?.metered ?? (source instanceof MeteredStore ? source : new MeteredStore(source));
    let store: ZfpStore | undefined;
    let stream: ChunkStoreStream | undefined;
    try {
      store = prepared?.store ?? (await openStore(metered, name, options.open));
      const fetcher = prepared?.fetcher ?? new ChunkFetcher(store, { maxInFlight: options.maxInFlight ?? 8 });
      // a prepared fetcher asked fewer at once: the session asks as many as its own would
      fetcher.maxInFlight = options.maxInFlight ?? 8;
      const fetched = prepared?.fetched ?? new FetchedChunks(store);
      fetcher.onChunk((level, chunk, bytes, fromCache) => fetched.add(level, chunk, bytes, fromCache));
      const budget = typeof options.budget === 'number' ? new GpuBudget(options.budget) : options.budget;
      const port = chunkedGpu(gpu, budget.meter, await storeEncoder(gpu, store), options.cacheOnly ?? false);
      const learnt = options.learnt?.(store);
      const view = options.view?.(store) ?? null;
      // one engine whichever way it is planned: by the view, or level by level
      const planner = view ? new CutPlanner() : new LevelPlanner(store.levels[0].layout);
      stream = await StoreStream.create<ChunkedVolume, IsosurfaceStats, Isosurface>(store, fetcher, port, budget, planner, { learnt });
      // surfaces of caches only are read live by the rays: a step on screen whose caches a step that did
      // not fit computed on is computed again rather than taken as shown
      if (options.cacheOnly) stream.setKeepCaches(true);
      options.setup?.(stream);
      if (view) await stream.setView(view);
      return new StoreSession(name, store, metered, fetcher, port, stream, fetched);
    } catch (e) {
      stream?.destroy();
      store?.close?.();
      throw e;
    }
  }
}
