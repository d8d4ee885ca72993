// The CLI's store input (`extract` / `bench` STORE --level L): a store URL
// or folder, one level fetched through the chunk fetcher (8 requests in
// flight) and assembled into one zfp stream on the GPU (assemble.ts: block
// reordering, no decode). Until the GPU chunk pool (ChunkedVolume) is in,
// this fetches every chunk of the level; the record says how much.
import { existsSync } from 'node:fs';
import { join } from 'node:path';
import { loadZfpStream } from '../zfp/gpu-stream.ts';
import { assembleLevelStream, assemblyLimit } from './assemble.ts';
import { ChunkFetcher } from './fetch/chunk-fetcher.ts';
import type { ChunkIndex } from './types.ts';
import { StoreError } from './zarr/errors.ts';
import { isStoreUrl, storeForLocation } from './zarr/node-store.ts';
import { openZfpStore } from './zarr/open-store.ts';
import { MeteredStore } from './zarr/stores.ts';

/** A URL, or a folder with a zarr.json at its root. */
export function isStoreInput(input: string): boolean {
  return isStoreUrl(input) || existsSync(join(input, 'zarr.json'));
}

export interface StoreRecord {
  store: string;
  level: number;
  levels: number;
  dims: [number, number, number];
  chunkEdge: number;
  rate: number;
  /** Chunks fetched / chunks of the level. */
  chunks: number;
  levelChunks: number;
  /** Bytes through the store: chunk bytes, and everything (metadata, shard indexes) at the end. */
  chunkBytesFetched: number;
  bytesFetched: number;
  metadataBytes: number;
  requests: number;
  /** Every chunk of every level (what a full download would be). */
  storeChunkBytes: number;
  fetchMs: number;
}

export async function openStoreInput(device: GPUDevice, input: string, level: number | undefined, onError: (message: string) => void) {
  const metered = new MeteredStore(storeForLocation(input));
  const store = await openZfpStore(metered, input);
  const L = level ?? 0;
  if (!Number.isInteger(L) || L < 0 || L >= store.levels.length) {
    throw new StoreError('layout', `${input}: --level ${level} does not exist (levels 0 to ${store.levels.length - 1})`);
  }
  const lv = store.levels[L];
  const limit = assemblyLimit(lv.layout, 2 ** 31); // the assembled stream is one CPU buffer before upload
  if (limit) throw new StoreError('layout', `${limit}; pick a coarser --level (the chunk pool, which needs no whole stream, is not merged yet)`);
  const fetcher = new ChunkFetcher(store, { maxInFlight: 8, cacheBytes: lv.storedBytes + 1 });
  const chunks = new Map<ChunkIndex, Uint8Array>();
  let failure: StoreError | null = null;
  fetcher.onChunk((_l, c, bytes) => chunks.set(c, bytes));
  fetcher.onError((_l, _c, e) => { failure ??= e; onError(e.message); });
  const t0 = performance.now();
  fetcher.want(L, Array.from({ length: lv.chunkCount }, (_, i) => i));
  await fetcher.idle();
  const fetchMs = performance.now() - t0;
  if (failure) throw failure;
  const bytes = assembleLevelStream(lv.layout, (c) => chunks.get(c)!);
  const stream = loadZfpStream(device, bytes, `${input} level ${L}`);
  const record: StoreRecord = {
    store: input, level: L, levels: store.levels.length, dims: lv.layout.dims, chunkEdge: lv.layout.chunkEdge, rate: lv.layout.rate,
    chunks: chunks.size, levelChunks: lv.chunkCount, chunkBytesFetched: fetcher.counters.bytesFetched,
    bytesFetched: metered.meter.bytes, metadataBytes: store.metadataBytes, requests: metered.meter.requests,
    storeChunkBytes: store.levels.reduce((a, l) => a + l.storedBytes, 0), fetchMs,
  };
  const how = `Zarr store, level ${L} of ${store.levels.length} (${lv.layout.dims.join('x')}, ${lv.layout.chunkEdge}^3 chunks, rate ${lv.layout.rate}), ` +
    `${record.chunks} chunks fetched (${record.bytesFetched} bytes with metadata)`;
  return { stream, how, rate: lv.layout.rate, notes: store.notes, fileName: `${input} level ${L}`, store: record };
}
