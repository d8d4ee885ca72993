// Fetches the chunks a surface needs: a bounded number of requests in
// flight, in the caller's priority order (nearest first), each cancellable.
// `want` replaces the wanted list (newest wins): queued chunks no longer
// wanted are dropped and requests in flight for them are aborted. The store
// tries each request again while that can help (zarr/retrying-store.ts: the
// one place requests are retried); a chunk whose request still failed is
// reported, and is not asked for again
// until its cool-down has passed (5 s, doubling per failure up to 2 min):
// asked for sooner, its last error is reported again at once, so the caller
// keeps what it shows and tries later (`retryAt`). Fetched chunks go into a
// CPU-side LRU bounded in bytes, so scrubbing back (or a chunk evicted from
// the GPU pool) does not fetch again.
import type { GetOptions } from '@zarrita/storage';
import type { ChunkIndex } from '../types.ts';
import { isAbort, StoreError } from '../zarr/errors.ts';
import { ByteLru } from './lru-bytes.ts';

export interface ChunkSource {
  readChunk(level: number, chunk: ChunkIndex, options?: GetOptions): Promise<Uint8Array>;
  /** Whether the bytes stand for a chunk absent from the store (not counted as fetched, not cached). */
  isAbsent?(bytes: Uint8Array): boolean;
}

export interface FetcherOptions {
  /** Requests in flight at most (default 8). */
  maxInFlight?: number;
  /** A failed chunk is not asked for again before this; doubles per failure up to 2 min (default 5 s). */
  coolDownMs?: number;
  /** CPU-side cache of compressed chunks, bytes (default 256 MiB). */
  cacheBytes?: number;
  /** Injected in tests: the clock (cool-downs, throughput). */
  now?: () => number;
}

export interface FetchCounters {
  /** Chunk bytes received (retries and later-aborted requests excluded). */
  bytesFetched: number;
  /** Requests started (retries included). */
  requests: number;
  inFlight: number;
  /** Requests aborted because their chunk was no longer wanted. */
  aborted: number;
  /** Chunks served from the CPU-side cache. */
  cacheHits: number;
  /** Chunk failures reported (a chunk asked for again during its cool-down is not counted again). */
  failed: number;
  /** bytesFetched / seconds with at least one request in flight. */
  throughputBytesPerSecond: number;
  /** CPU-side cache: bytes held and its capacity. */
  cacheBytes: number;
  cacheCapacityBytes: number;
}

export type ChunkListener = (level: number, chunk: ChunkIndex, bytes: Uint8Array, fromCache: boolean) => void;
/** `repeated`: the chunk was asked for during its cool-down, and this is its last error again. */
export type ChunkErrorListener = (level: number, chunk: ChunkIndex, error: StoreError, repeated: boolean) => void;

const key = (level: number, chunk: ChunkIndex) => `${level}:${chunk}`;

export class ChunkFetcher {
  /** Requests in flight at most (may be raised: a prefetch's fetcher taken over by the session that shows its time point). */
  maxInFlight: number;
  readonly #coolDownMs: number;
  readonly #now: () => number;
  readonly #cache: ByteLru<string>;
  #queue: Array<{ level: number; chunk: ChunkIndex }> = [];
  #wanted = new Set<string>();
  #inFlight = new Map<string, AbortController>();
  /** Chunks whose last request failed: the error, how often, and when they may be asked for again. */
  #failed = new Map<string, { error: StoreError; failures: number; retryAt: number }>();
  #chunkListeners = new Set<ChunkListener>();
  #errorListeners = new Set<ChunkErrorListener>();
  #idleWaiters: Array<() => void> = [];
  #busySince = -1;
  #busyMs = 0;
  #counts = { bytesFetched: 0, requests: 0, aborted: 0, cacheHits: 0, failed: 0 };

  constructor(
    readonly source: ChunkSource,
    options: FetcherOptions = {},
  ) {
    this.maxInFlight = Math.max(1, options.maxInFlight ?? 8);
    this.#coolDownMs = options.coolDownMs ?? 5000;
    this.#now = options.now ?? (() => performance.now());
    this.#cache = new ByteLru(options.cacheBytes ?? 256 << 20);
  }

  onChunk(l: ChunkListener): () => void {
    this.#chunkListeners.add(l);
    return () => this.#chunkListeners.delete(l);
  }
  onError(l: ChunkErrorListener): () => void {
    this.#errorListeners.add(l);
    return () => this.#errorListeners.delete(l);
  }

  get counters(): FetchCounters {
    const busy = this.#busyMs + (this.#busySince >= 0 ? this.#now() - this.#busySince : 0);
    return {
      ...this.#counts,
      inFlight: this.#inFlight.size,
      throughputBytesPerSecond: busy > 0 ? (this.#counts.bytesFetched * 1000) / busy : 0,
      cacheBytes: this.#cache.bytes,
      cacheCapacityBytes: this.#cache.capacityBytes,
    };
  }

  /** The chunk's bytes if the CPU-side cache holds them (counts as a hit). */
  cached(level: number, chunk: ChunkIndex): Uint8Array | undefined {
    return this.#cache.get(key(level, chunk));
  }

  /**
   * The chunks wanted now, most urgent first; replaces the previous list.
   * Cached chunks are delivered at once (synchronously), the rest fetched.
   * A chunk that failed and is still cooling down is not fetched: its last
   * error is reported again (on a microtask).
   */
  want(level: number, chunks: readonly ChunkIndex[]): void {
    this.wantAll(chunks.map((chunk) => ({ level, chunk })));
  }

  /** As want, for chunks of several levels at once (the view cut: each region at its level), most urgent first. */
  wantAll(items: readonly { level: number; chunk: ChunkIndex }[]): void {
    this.#wanted = new Set(items.map(({ level, chunk }) => key(level, chunk)));
    for (const [k, ctl] of this.#inFlight) {
      if (!this.#wanted.has(k)) {
        ctl.abort(new DOMException('no longer needed', 'AbortError'));
        this.#inFlight.delete(k);
        this.#counts.aborted++;
      }
    }
    this.#queue = [];
    const now = this.#now();
    const stillFailed: Array<[number, ChunkIndex, StoreError]> = [];
    for (const { level, chunk } of items) {
      const k = key(level, chunk);
      const hit = this.#cache.get(k);
      const failed = this.#failed.get(k);
      if (hit) {
        this.#counts.cacheHits++;
        for (const l of this.#chunkListeners) l(level, chunk, hit, true);
      } else if (failed && failed.retryAt > now) {
        stillFailed.push([level, chunk, failed.error]);
      } else if (!this.#inFlight.has(k)) {
        this.#queue.push({ level, chunk });
      }
    }
    this.#pump();
    this.#checkIdle();
    if (stillFailed.length > 0) {
      const wanted = this.#wanted;
      queueMicrotask(() => {
        for (const [level, chunk, error] of stillFailed) {
          if (this.#wanted !== wanted) return; // a newer list replaced this one
          for (const l of this.#errorListeners) l(level, chunk, error, true);
        }
      });
    }
  }

  /** When a failed chunk may be asked for again (ms on this fetcher's clock), or undefined if it has not failed. */
  retryAt(level: number, chunk: ChunkIndex): number | undefined {
    return this.#failed.get(key(level, chunk))?.retryAt;
  }

  /** Stops everything wanted (e.g. the store is closed). */
  cancelAll(): void {
    this.want(0, []);
  }

  /** Forgets every failure: failed chunks are fetched again when next wanted. */
  retryFailed(): void {
    this.#failed.clear();
  }

  /** Resolves once nothing is queued or in flight. */
  idle(): Promise<void> {
    if (this.#queue.length === 0 && this.#inFlight.size === 0) return Promise.resolve();
    return new Promise((r) => this.#idleWaiters.push(r));
  }

  #checkIdle(): void {
    if (this.#inFlight.size === 0 && this.#busySince >= 0) {
      this.#busyMs += this.#now() - this.#busySince;
      this.#busySince = -1;
    }
    if (this.#queue.length === 0 && this.#inFlight.size === 0) {
      const w = this.#idleWaiters;
      this.#idleWaiters = [];
      for (const r of w) r();
    }
  }

  #pump(): void {
    while (this.#inFlight.size < this.maxInFlight && this.#queue.length > 0) {
      const { level, chunk } = this.#queue.shift()!;
      const k = key(level, chunk);
      const ctl = new AbortController();
      this.#inFlight.set(k, ctl);
      if (this.#busySince < 0) this.#busySince = this.#now();
      void this.#run(level, chunk, k, ctl);
    }
  }

  async #run(level: number, chunk: ChunkIndex, k: string, ctl: AbortController): Promise<void> {
    let error: StoreError | null = null;
    let bytes: Uint8Array | null = null;
    // An abort that is not ours (a shard index shared with a chunk whose request was aborted) is tried again at once;
    // every other failure is the store's final word (it retried what could help).
    for (let foreignAborts = 0; !ctl.signal.aborted; ) {
      try {
        this.#counts.requests++;
        bytes = await this.source.readChunk(level, chunk, { signal: ctl.signal });
        break;
      } catch (e) {
        if (ctl.signal.aborted) break;
        if (isAbort(e) || (e as StoreError)?.kind === 'aborted') {
          if (++foreignAborts <= 8) continue;
          error = new StoreError('aborted', `chunk ${chunk} of level ${level}: aborted`, { cause: e });
          break;
        }
        error =
          e instanceof StoreError
            ? e
            : new StoreError('unreachable', `chunk ${chunk} of level ${level}: ${(e as Error).message}`, { cause: e });
        break;
      }
    }
    if (this.#inFlight.get(k) !== ctl) return; // aborted (and counted) by want()
    this.#inFlight.delete(k);
    if (bytes && !ctl.signal.aborted) {
      this.#failed.delete(k);
      if (!this.source.isAbsent?.(bytes)) {
        this.#counts.bytesFetched += bytes.length;
        this.#cache.set(k, bytes);
      }
      for (const l of this.#chunkListeners) l(level, chunk, bytes, false);
    } else if (error) {
      this.#counts.failed++;
      const failures = (this.#failed.get(k)?.failures ?? 0) + 1;
      const wait = Math.min(120_000, this.#coolDownMs * 2 ** (failures - 1));
      this.#failed.set(k, { error, failures, retryAt: this.#now() + wait });
      for (const l of this.#errorListeners) l(level, chunk, error, false);
    }
    this.#pump();
    this.#checkIdle();
  }
}
