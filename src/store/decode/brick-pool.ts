// Bricks of a store of lossless chunks read by a pool of Web Workers
// (brick-worker.ts), so decoding never holds the page's main thread. A brick
// goes to the worker of the source chunk holding its first voxel, so bricks
// cut from one chunk (planes, 64x128x128 chunks) find it decoded in that
// worker's cache. A read whose request is aborted (the brick is no longer
// wanted) is cancelled in its worker, which drops it before fetching or
// decoding it if it has not started (brick-queue.ts). What the workers'
// stores fetched is added to the page's meters as replies come.
import type { GetOptions } from '@zarrita/storage';
import type { ChunkIndex } from '../types.ts';
import { StoreError, type StoreErrorKind } from '../zarr/errors.ts';
import type { RetryCounters } from '../zarr/retrying-store.ts';
import type { BrickSource, SourceLevel } from '../zarr/source-store.ts';
import type { StoreMeter } from '../zarr/stores.ts';
import type { BrickCancel, BrickInit, BrickReply, BrickRequest, QueueReport } from './brick-protocol.ts';
import type { StoreSpec } from './store-spec.ts';

/** Workers for a machine: one per core but one, 1 to 4. */
export function brickWorkerCount(): number {
  const cores = typeof navigator === 'undefined' ? 2 : (navigator.hardwareConcurrency ?? 2);
  return Math.max(1, Math.min(4, cores - 1));
}

export class BrickWorkerPool implements BrickSource {
  readonly counters = { chunksDecoded: 0, bytesDecoded: 0, decodeMs: 0, nonFinite: 0 };
  readonly valueRanges: Array<[number, number]>;
  readonly #workers: Worker[];
  readonly #decodeByWorker: BrickSource['counters'][];
  readonly #pending = new Map<number, { resolve: (b: Uint8Array) => void; reject: (e: unknown) => void; level: number }>();
  /** Per worker, its queue as its last reply said (reads held, the most held at once). */
  readonly #queues: QueueReport[];
  #next = 0;
  #closed = false;

  get workerCount(): number {
    return this.#workers.length;
  }

  constructor(
    private readonly levels: readonly SourceLevel[],
    spec: StoreSpec,
    format: 2 | 3,
    private readonly meter: StoreMeter,
    private readonly retries: RetryCounters,
    count = brickWorkerCount(),
    cacheBytes = 256 << 20,
  ) {
    this.valueRanges = levels.map(() => [Infinity, -Infinity]);
    const init: BrickInit = {
      type: 'init',
      spec,
      format,
      levels: levels.map((l) => ({
        path: l.path,
        spatial: l.spatial,
        fixed: [...l.fixed],
        chunkXYZ: l.chunkXYZ,
        layout: l.layout,
      })),
      cacheBytes: Math.max(64 << 20, Math.floor(cacheBytes / count)),
    };
    this.#decodeByWorker = [];
    this.#queues = Array.from({ length: count }, () => ({ held: 0, maxHeld: 0 }));
    this.#workers = Array.from({ length: count }, (_, i) => {
      const w = new Worker(new URL('./brick-worker.ts', import.meta.url), { type: 'module', name: `bricks ${i}` });
      this.#decodeByWorker.push({ chunksDecoded: 0, bytesDecoded: 0, decodeMs: 0, nonFinite: 0 });
      w.onmessage = (e: MessageEvent<BrickReply>) => this.#reply(i, e.data);
      w.onerror = (e) => this.#failAll(new StoreError('corrupt', `a brick worker stopped: ${e.message}`));
      w.postMessage(init);
      return w;
    });
  }

  /**
   * Bricks the workers hold (waiting or being read) as their last replies
   * said, and the most they held (each worker's most, summed: an upper
   * bound): what a moving camera leaves behind. Cancelled reads leave a
   * worker's queue when it gets the cancel (brick-queue.ts).
   */
  get queue(): { queued: number; maxQueued: number } {
    return {
      queued: this.#queues.reduce((a, q) => a + q.held, 0),
      maxQueued: this.#queues.reduce((a, q) => a + q.maxHeld, 0),
    };
  }

  read(level: number, brick: ChunkIndex, options?: GetOptions): Promise<Uint8Array> {
    if (this.#closed) return Promise.reject(new StoreError('aborted', `${this.levels[level].layout.name}: the store was closed`));
    const signal = options?.signal;
    signal?.throwIfAborted();
    const id = this.#next++;
    const worker = this.#workers[this.#workerOf(level, brick)];
    return new Promise<Uint8Array>((resolve, reject) => {
      // an abort ends the wait and cancels the read in its worker: dropped there unless it has started
      const onAbort = () => {
        this.#pending.delete(id);
        worker.postMessage({ type: 'cancel', id } satisfies BrickCancel);
        reject(signal!.reason ?? new DOMException('aborted', 'AbortError'));
      };
      signal?.addEventListener('abort', onAbort, { once: true });
      this.#pending.set(id, {
        level,
        resolve: (b) => {
          signal?.removeEventListener('abort', onAbort);
          resolve(b);
        },
        reject: (e) => {
          signal?.removeEventListener('abort', onAbort);
          reject(e);
        },
      });
      worker.postMessage({ type: 'read', id, level, brick } satisfies BrickRequest);
    });
  }

  /** The worker of the source chunk holding the brick's first voxel. */
  #workerOf(level: number, brick: ChunkIndex): number {
    const L = this.levels[level];
    const { chunkEdge: B, chunkGrid } = L.layout;
    const [gx, gy] = chunkGrid;
    const b = [brick % gx, Math.floor(brick / gx) % gy, Math.floor(brick / (gx * gy))];
    const k = b.map((v, a) => Math.floor((v * B) / L.chunkXYZ[a]));
    const h = (k[0] * 73856093) ^ (k[1] * 19349663) ^ (k[2] * 83492791) ^ (level * 2654435761);
    return (h >>> 0) % this.#workers.length;
  }

  #reply(worker: number, m: BrickReply): void {
    this.meter.bytes += m.meter.bytes;
    this.meter.requests += m.meter.requests;
    this.retries.retries += m.meter.retries;
    this.retries.failed += m.meter.failed;
    if (m.queue) this.#queues[worker] = m.queue;
    const p = this.#pending.get(m.id);
    this.#pending.delete(m.id);
    if (m.type === 'done') {
      this.#decodeByWorker[worker] = m.decode;
      for (const k of ['chunksDecoded', 'bytesDecoded', 'decodeMs', 'nonFinite'] as const)
        this.counters[k] = this.#decodeByWorker.reduce((a, c) => a + c[k], 0);
      if (p) {
        const r = this.valueRanges[p.level];
        r[0] = Math.min(r[0], m.range[0]);
        r[1] = Math.max(r[1], m.range[1]);
        p.resolve(m.bytes);
      }
    } else if (p) {
      const e = m.error;
      if (e.name === 'AbortError') p.reject(new DOMException(e.message, 'AbortError'));
      else p.reject(new StoreError((e.kind as StoreErrorKind | null) ?? 'corrupt', e.message));
    }
  }

  #failAll(e: Error): void {
    for (const p of this.#pending.values()) p.reject(e);
    this.#pending.clear();
  }

  destroy(): void {
    this.#closed = true;
    for (const w of this.#workers) w.terminate();
    this.#failAll(new StoreError('aborted', 'the store was closed'));
  }
}
