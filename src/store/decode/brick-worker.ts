// A Web Worker that reads bricks of a store of lossless chunks
// (source-store.ts BrickReader) off the main thread: it opens the store
// again from its spec, fetches and decodes the chunks (zarrita's codecs),
// assembles and pads each brick, and transfers its float32 values back. Reads
// run a few at a time (brick-queue.ts): one the page cancels before it starts
// is dropped unread. Protocol: brick-protocol.ts.
import * as zarr from 'zarrita';
import { StoreError } from '../zarr/errors.ts';
import { MetadataMemo } from '../zarr/metadata.ts';
import { RetryingStore } from '../zarr/retrying-store.ts';
import { BrickReader, type SourceLevel } from '../zarr/source-store.ts';
import { MeteredStore } from '../zarr/stores.ts';
import type { BrickCancel, BrickInit, BrickReply, BrickRequest } from './brick-protocol.ts';
import { BrickQueue } from './brick-queue.ts';
import { storeFromSpec } from './store-spec.ts';

declare const self: { postMessage(m: unknown, transfer?: Transferable[]): void; onmessage: ((e: MessageEvent) => void) | null };

let initMessage: BrickInit | null = null;
let ready: Promise<{ reader: BrickReader; metered: MeteredStore; retrying: RetryingStore }> | null = null;
const reported = { bytes: 0, requests: 0, retries: 0, failed: 0 };

async function init(m: BrickInit) {
  const metered = new MeteredStore(storeFromSpec(m.spec));
  const retrying = new RetryingStore(metered);
  const mem = new MetadataMemo(retrying);
  const levels: SourceLevel[] = [];
  for (const l of m.levels) {
    const loc = zarr.root(mem).resolve(l.path || '/');
    const array = m.format === 3 ? await zarr.open.v3(loc, { kind: 'array' }) : await zarr.open.v2(loc, { kind: 'array', attrs: false });
    levels.push({ path: l.path, array, spatial: l.spatial, fixed: new Map(l.fixed), chunkXYZ: l.chunkXYZ, layout: l.layout });
  }
  return { reader: new BrickReader(levels, m.cacheBytes), metered, retrying };
}

const queue = new BrickQueue(
  read,
  (m, transfer) => self.postMessage(m, transfer),
  () => ({ bytes: 0, requests: 0, retries: 0, failed: 0 }),
);

self.onmessage = (e: MessageEvent) => {
  const m = e.data as BrickInit | BrickRequest | BrickCancel;
  if (m.type === 'init') initMessage = m;
  else if (m.type === 'cancel') queue.cancel(m.id);
  else queue.read(m);
};

async function read(m: BrickRequest, signal: AbortSignal): Promise<{ reply: BrickReply; transfer: Transferable[] }> {
  let reply: BrickReply;
  const transfer: Transferable[] = [];
  let w: Awaited<NonNullable<typeof ready>> | null = null;
  try {
    if (!initMessage) throw new Error('the brick worker was not initialised');
    // opened on first use; an open that failed (the network) is tried again by the next read
    if (!ready) {
      ready = init(initMessage);
      ready.catch(() => {
        ready = null;
      });
    }
    w = await ready;
    const bytes = await w.reader.read(m.level, m.brick, { signal });
    transfer.push(bytes.buffer as ArrayBuffer);
    reply = { type: 'done', id: m.id, bytes, range: w.reader.valueRanges[m.level], decode: { ...w.reader.counters }, meter: delta(w) };
  } catch (e) {
    const err = e as Error & { kind?: string };
    reply = {
      type: 'fail',
      id: m.id,
      error: {
        name: err?.name ?? 'Error',
        kind: e instanceof StoreError ? e.kind : (err?.kind ?? null),
        message: err?.message ?? String(e),
      },
      meter: w ? delta(w) : { bytes: 0, requests: 0, retries: 0, failed: 0 },
    };
  }
  return { reply, transfer };
}

/** What the store did since the last reply (the main thread adds it to the store's meters). */
function delta(w: { metered: MeteredStore; retrying: RetryingStore }) {
  const now = {
    bytes: w.metered.meter.bytes,
    requests: w.metered.meter.requests,
    retries: w.retrying.counters.retries,
    failed: w.retrying.counters.failed,
  };
  const d = {
    bytes: now.bytes - reported.bytes,
    requests: now.requests - reported.requests,
    retries: now.retries - reported.retries,
    failed: now.failed - reported.failed,
  };
  Object.assign(reported, now);
  return d;
}
