// The CLI's store input (`extract` / `bench` STORE --level L): a store URL
// or folder, streamed at level L only (pinned-level.ts): each isovalue
// fetches the chunks its surface needs (8 requests in flight) into the
// level's GPU pool of compressed chunks; the record says how much came over.
import { existsSync, mkdirSync, readFileSync, rmSync, statSync, writeFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import type { GpuContext } from '../gpu/device.ts';
import type { Isosurface } from '../isosurface/isosurface.ts';
import type { IsosurfaceStats } from '../isosurface/types.ts';
import type { ChunkedVolume } from '../zfp/chunked-volume.ts';
import { defaultMemoryBudget } from '../isosurface/budget.ts';
import { ChunkFetcher } from './fetch/chunk-fetcher.ts';
import { chunkedGpu, createChunkStream, storeEncoder } from './gpu-port.ts';
import { PinnedLevelSurface } from './pinned-level.ts';
import { storeRateChooser } from './rate.ts';
import { StoreError } from './zarr/errors.ts';
import { isStoreUrl, storeForLocation } from './zarr/node-store.ts';
import { openStore } from './zarr/open-store.ts';
import type { SourceInfo } from './zarr/source-store.ts';
import { MeteredStore } from './zarr/stores.ts';
import { rangesSidecarFiles } from './zarr/ranges-sidecar-files.ts';
import { isZipStoreName } from './zarr/zip-store.ts';
import type { ZfpStore } from './zarr/store.ts';
import type { StreamGpuBytes } from './stream-port.ts';
import type { ChunkedStreamGpu } from './gpu-port.ts';
import { type ViewRequest, viewSpecFor } from './view/view-request.ts';
import { ViewStream } from './view/view-stream.ts';
import { ViewCutSurface } from './view/view-surface.ts';

/** --level names a level the store does not have (a wrong command line, not a data failure). */
export class NoSuchLevelError extends Error {
  constructor(message: string) {
    super(message);
    this.name = 'NoSuchLevelError';
  }
}

/** A URL, or a folder with Zarr metadata at its root (v3 zarr.json, v2 .zgroup or .zarray). */
export function isStoreInput(input: string): boolean {
  return isStoreUrl(input) || isZipStoreName(input) || ['zarr.json', '.zgroup', '.zarray'].some((f) => existsSync(join(input, f)));
}

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
  /** Requests tried again after a transient failure, requests that failed for good, and what the failed tries saw. */
  retries: number;
  failedRequests: number;
  faults: Record<string, number>;
}

export interface StoreInput {
  surface: PinnedLevelSurface | ViewCutSurface;
  how: string;
  rate: number;
  notes: string[];
  fileName: string;
  /** The store's figures so far. */
  record(): StoreRecord;
  /**
   * A store of lossless chunks: writes the brick ranges known now (learnt
   * as bricks arrived, or a level's once resident whole) as a ranges sidecar
   * folder (--save-ranges); absent for a zfp store.
   */
  saveRanges?(dir: string): Promise<{ known: number; bricks: number }>;
}

export interface StoreInputOptions {
  /** The level to stream (default 0). */
  level?: number;
  /** The GPU memory of the whole stream (everything it holds); by default the pipeline's default budget. */
  budget?: number;
  /** How long one request is tried (default 30 s; retrying-store.ts). */
  deadlineMs?: number;
  /** Stores of lossless chunks: the GPU's zfp rate (default 8); time point and channel (default 0). */
  rate?: number;
  time?: number;
  channel?: number;
  /** Per-brick ranges written apart (--ranges-only), a URL or folder. */
  ranges?: string;
  /** Refine by this view instead of streaming one level (--view-box, --view): a mixed-level surface (src/store/view/). */
  view?: ViewRequest;
}

export async function openStoreInput(gpu: GpuContext, input: string, opts: StoreInputOptions): Promise<StoreInput> {
  const metered = new MeteredStore(storeForLocation(input));
  const store = await openStore(metered, input, {
    ...(opts.deadlineMs === undefined ? {} : { retry: { deadlineMs: opts.deadlineMs } }),
    rate: opts.rate,
    chooseRate: storeRateChooser(gpu),
    time: opts.time,
    channel: opts.channel,
    ...(opts.ranges === undefined ? {} : { ranges: { store: storeForLocation(opts.ranges), name: opts.ranges } }),
  });
  if (!store.source && opts.ranges !== undefined)
    store.notes.push(`--ranges is for stores of lossless chunks; this store's chunks are zfp, with their own ranges or none`);
  if (!store.source && opts.rate !== undefined && opts.rate !== store.levels[0].layout.rate)
    store.notes.push(
      `--rate ${opts.rate} is for stores of lossless chunks; this store's chunks are zfp at rate ${store.levels[0].layout.rate}, used as they are`,
    );
  const { level } = opts;
  const L = level ?? 0;
  if (!Number.isInteger(L) || L < 0 || L >= store.levels.length) {
    throw new NoSuchLevelError(`${input}: --level ${level} does not exist (levels 0 to ${store.levels.length - 1})`);
  }
  const lv = store.levels[L];
  if (lv.unusable) throw new StoreError('layout', `${input}: --level ${L}: ${lv.unusable}`);
  const fetcher = new ChunkFetcher(store, { maxInFlight: 8 });
  const fetched = new Set<number>();
  let chunkBytes = 0;
  fetcher.onChunk((l, c, bytes, fromCache) => {
    if (l !== L || fromCache || fetched.has(c) || store.isAbsent(bytes)) return;
    fetched.add(c);
    chunkBytes += bytes.byteLength;
  });
  const budgetBytes = opts.budget ?? defaultMemoryBudget(gpu.device.limits);
  const port = chunkedGpu(gpu, undefined, await storeEncoder(gpu, store));
  if (opts.view) return viewInput(input, store, metered, fetcher, port, budgetBytes, opts.view);
  const controller = await createChunkStream(store, fetcher, port, budgetBytes);
  const surface = new PinnedLevelSurface(controller, L);
  const record = (): StoreRecord =>
    storeRecord(input, store, metered, L, L, {
      chunks: fetched.size,
      chunkBytes,
      budgetBytes,
      gpu: controller.gpuBytes,
      peak: port.meter.peak,
    });
  const kind = store.source
    ? `${store.source.format} store of ${store.source.dtype} (${store.source.codecs.join(' + ') || 'uncompressed'}), level ${L} of ${store.levels.length} (${lv.layout.dims.join('x')}, ${lv.layout.chunkEdge}^3 bricks compressed on the GPU at rate ${lv.layout.rate})`
    : `Zarr store, level ${L} of ${store.levels.length} (${lv.layout.dims.join('x')}, ${lv.layout.chunkEdge}^3 chunks, rate ${lv.layout.rate})`;
  const how = `${kind}, ` + `streamed: the chunks each surface needs, within ${(budgetBytes / 2 ** 20).toFixed(0)} MiB of GPU memory`;
  return {
    surface,
    how,
    rate: lv.layout.rate,
    notes: store.notes,
    fileName: `${input} level ${L}`,
    record,
    // levels with range arrays: those; the others: what was learnt as bricks arrived, a level learnt in part included
    ...(store.source
      ? {
          saveRanges: async (dir: string) =>
            writeSidecar(store, dir, (l) => (store.levels[l].rangesPath ? controller.chunkRanges(l) : controller.learnt.level(l))),
        }
      : {}),
  };
}

/** Writes a ranges sidecar folder (ranges-sidecar-files.ts); an existing folder is replaced only when it is a ranges sidecar. */
function writeSidecar(store: ZfpStore, dir: string, ranges: (level: number) => Float32Array | null): { known: number; bricks: number } {
  const sidecar = rangesSidecarFiles(store, ranges);
  if (existsSync(dir)) {
    let isSidecar = false;
    try {
      isSidecar = statSync(dir).isDirectory() && readFileSync(join(dir, 'zarr.json'), 'utf8').includes('"zfpzarr_ranges"');
    } catch {
      // not a folder with a zarr.json
    }
    if (!isSidecar) throw new StoreError('layout', `${dir}: exists and is not a ranges sidecar; give a new folder to --save-ranges`);
    rmSync(dir, { recursive: true, force: true });
  }
  for (const [path, bytes] of sidecar.files) {
    mkdirSync(dirname(join(dir, path)), { recursive: true });
    writeFileSync(join(dir, path), bytes);
  }
  return { known: sidecar.known, bricks: sidecar.bricks };
}

/**
 * A store refined by a view (--view-box, --view): every level the cut uses,
 * each region at the level the view needs; the record's `level` is the
 * finest level drawn, `chunks` the distinct chunks put at any level.
 */
async function viewInput(
  input: string,
  store: ZfpStore,
  metered: MeteredStore,
  fetcher: ChunkFetcher,
  port: ChunkedStreamGpu,
  budgetBytes: number,
  request: ViewRequest,
): Promise<StoreInput> {
  let view;
  try {
    view = viewSpecFor(
      request,
      store.levels.map((l) => l.layout),
      store.voxelSize,
    );
  } catch (e) {
    throw new StoreError('layout', `${input}: ${(e as Error).message}`);
  }
  const fetched = new Set<number>();
  let chunkBytes = 0;
  fetcher.onChunk((l, c, bytes, fromCache) => {
    const k = l * 2 ** 32 + c;
    if (fromCache || fetched.has(k) || store.isAbsent(bytes)) return;
    fetched.add(k);
    chunkBytes += bytes.byteLength;
  });
  const stream = await ViewStream.create<ChunkedVolume, IsosurfaceStats, Isosurface>(store, fetcher, port, budgetBytes);
  stream.retryFailed = false; // the CLI reports a chunk that failed (after the store's own retries)
  stream.skirts = request.skirts ?? true;
  await stream.setView(view);
  const surface = new ViewCutSurface(stream);
  const lv0 = store.levels[0];
  const record = (): StoreRecord =>
    storeRecord(input, store, metered, Math.min(...(stream.shown?.levels.map((l) => l.level) ?? [0])), 0, {
      chunks: fetched.size,
      chunkBytes,
      budgetBytes,
      gpu: stream.gpuBytes,
      peak: port.meter.peak,
    });
  const how =
    `Zarr store of ${store.levels.length} levels (level 0 ${lv0.layout.dims.join('x')}, ${lv0.layout.chunkEdge}^3 chunks, rate ${lv0.layout.rate}), ` +
    `refined by the view (each region at the level whose voxels project to at most ${view.tolerancePx} px), within ${(budgetBytes / 2 ** 20).toFixed(0)} MiB of GPU memory`;
  // levels with range arrays (a sidecar given): those; the others: what the stream learnt as bricks arrived
  const saveRanges = async (dir: string) => {
    await stream.learnSettled();
    return writeSidecar(store, dir, (l) => (store.levels[l].rangesPath ? stream.chunkRanges(l) : stream.learnt.level(l)));
  };
  return {
    surface,
    how,
    rate: lv0.layout.rate,
    notes: store.notes,
    fileName: `${input} (view)`,
    record,
    ...(store.source ? { saveRanges } : {}),
  };
}

/**
 * The record of a store input: `level` the level streamed (or the finest a
 * view drew), `layoutLevel` whose dims, chunks and rate it gives.
 */
function storeRecord(
  input: string,
  store: ZfpStore,
  metered: MeteredStore,
  level: number,
  layoutLevel: number,
  got: { chunks: number; chunkBytes: number; budgetBytes: number; gpu: StreamGpuBytes; peak: number },
): StoreRecord {
  const lv = store.levels[layoutLevel];
  return {
    store: input,
    level,
    levels: store.levels.length,
    dims: lv.layout.dims,
    chunkEdge: lv.layout.chunkEdge,
    rate: lv.layout.rate,
    chunks: got.chunks,
    source: store.source,
    sourceValueRange: store.sourceValueRange?.(layoutLevel) ?? null,
    sourceDecode: store.sourceDecode?.() ?? null,
    voxelSize: store.voxelSize,
    unit: store.unit,
    levelChunks: lv.chunkCount,
    // a store of lossless chunks: what came over for the bricks (their source chunks), not the bricks' values
    chunkBytesFetched: store.source ? metered.meter.bytes - store.metadataBytes : got.chunkBytes,
    bytesFetched: metered.meter.bytes,
    metadataBytes: store.metadataBytes,
    requests: metered.meter.requests,
    storeChunkBytes: store.levels.reduce((a, l) => a + l.storedBytes, 0),
    budgetBytes: got.budgetBytes,
    gpuBytes: got.gpu.total,
    gpuPoolBytes: got.gpu.pools,
    gpuCacheBytes: got.gpu.cache,
    gpuVertexBytes: got.gpu.vertices,
    gpuPeakBytes: got.peak,
    retries: store.retries.retries,
    failedRequests: store.retries.failed,
    faults: { ...store.retries.faults },
  };
}
