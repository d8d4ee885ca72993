// The chunk fetcher against a scripted fake store: every request waits for
// the test to answer it, so the order, the bound on requests in flight,
// aborts, failures with their cool-down and the cache are checked without any timing.
import { describe, expect, it } from 'vitest';
import type { GetOptions } from '@zarrita/storage';
import { ChunkFetcher } from '../../../src/store/fetch/chunk-fetcher.ts';
import { StoreError } from '../../../src/store/zarr/errors.ts';

interface Pending {
  level: number;
  chunk: number;
  signal: AbortSignal;
  resolve(b: Uint8Array): void;
  reject(e: unknown): void;
}

class FakeStore {
  pending: Pending[] = [];
  started: string[] = [];
  readChunk(level: number, chunk: number, options?: GetOptions): Promise<Uint8Array> {
    this.started.push(`${level}:${chunk}`);
    return new Promise((resolve, reject) => {
      const signal = options!.signal!;
      const p = { level, chunk, signal, resolve, reject };
      this.pending.push(p);
      signal.addEventListener('abort', () => reject(signal.reason));
    });
  }
  /** Answers the oldest live request for this chunk. */
  answer(chunk: number, bytes = new Uint8Array(chunk + 1).fill(chunk & 255)): void {
    const i = this.pending.findIndex((p) => p.chunk === chunk && !p.signal.aborted);
    if (i < 0) throw new Error(`no request for chunk ${chunk}`);
    const [p] = this.pending.splice(i, 1);
    p.resolve(bytes);
  }
  fail(chunk: number, error: unknown): void {
    const i = this.pending.findIndex((p) => p.chunk === chunk && !p.signal.aborted);
    const [p] = this.pending.splice(i, 1);
    p.reject(error);
  }
  live(): number[] {
    return this.pending.filter((p) => !p.signal.aborted).map((p) => p.chunk);
  }
}

const settle = () => new Promise((r) => setTimeout(r, 0));

function setup(opts = {}) {
  const store = new FakeStore();
  let clock = 0;
  const fetcher = new ChunkFetcher(store, { now: () => clock, ...opts });
  const got: string[] = [];
  const errors: string[] = [];
  fetcher.onChunk((level, chunk, bytes, fromCache) => got.push(`${level}:${chunk}:${bytes.length}${fromCache ? ':cache' : ''}`));
  fetcher.onError((_l, chunk, e) => errors.push(`${chunk}:${e.kind}`));
  return {
    store,
    fetcher,
    got,
    errors,
    tick: (ms: number) => {
      clock += ms;
    },
  };
}

describe('ChunkFetcher', () => {
  it('keeps at most maxInFlight requests, in the given priority order', async () => {
    const { store, fetcher, got } = setup({ maxInFlight: 3 });
    fetcher.want(0, [5, 1, 9, 2, 7]);
    expect(store.live()).toEqual([5, 1, 9]);
    expect(fetcher.counters.inFlight).toBe(3);
    store.answer(1);
    await settle();
    expect(store.live()).toEqual([5, 9, 2]);
    for (const c of [5, 9, 2]) store.answer(c);
    await settle();
    store.answer(7);
    await fetcher.idle();
    expect(got).toEqual(['0:1:2', '0:5:6', '0:9:10', '0:2:3', '0:7:8']);
    expect(fetcher.counters).toMatchObject({ requests: 5, inFlight: 0, aborted: 0, bytesFetched: 2 + 6 + 10 + 3 + 8 });
  });

  it('newest wins: requests no longer wanted are aborted, wanted ones kept', async () => {
    const { store, fetcher, got } = setup({ maxInFlight: 2 });
    fetcher.want(0, [1, 2, 3, 4]);
    expect(store.live()).toEqual([1, 2]);
    fetcher.want(0, [2, 6]);
    expect(fetcher.counters.aborted).toBe(1);
    expect(store.live()).toEqual([2, 6]);
    store.answer(2);
    store.answer(6);
    await fetcher.idle();
    expect(got).toEqual(['0:2:3', '0:6:7']);
    expect(store.started).toEqual(['0:1', '0:2', '0:6']);
    // another level replaces everything
    fetcher.want(1, [0, 1]);
    fetcher.want(0, []);
    expect(fetcher.counters.aborted).toBe(3);
    await fetcher.idle();
  });

  it('serves chunks fetched before from the CPU cache, bounded in bytes (LRU)', async () => {
    const { store, fetcher, got } = setup({ cacheBytes: 25 });
    fetcher.want(0, [9, 4]); // 10 + 5 bytes
    store.answer(9);
    store.answer(4);
    await fetcher.idle();
    fetcher.want(0, [9]); // hit, now most recent
    expect(got.at(-1)).toBe('0:9:10:cache');
    fetcher.want(0, [11]); // 12 bytes: 27 > 25, evicts 4 (least recent)
    store.answer(11);
    await fetcher.idle();
    got.length = 0;
    fetcher.want(0, [9, 4, 11]);
    expect(got).toEqual(['0:9:10:cache', '0:11:12:cache']);
    expect(store.live()).toEqual([4]);
    store.answer(4);
    await fetcher.idle();
    expect(fetcher.counters).toMatchObject({ cacheHits: 3, requests: 4 });
    expect(fetcher.counters.cacheBytes).toBeLessThanOrEqual(25);
  });

  it('a failure is reported once (the store retried it), not fetched again during its cool-down; a missing chunk too', async () => {
    const { store, fetcher, errors, got } = setup();
    fetcher.want(0, [3, 4]);
    store.answer(3);
    store.fail(4, new StoreError('http', 'HTTP 503'));
    await fetcher.idle();
    expect(got).toEqual(['0:3:4']);
    expect(errors).toEqual(['4:http']);
    expect(fetcher.counters).toMatchObject({ failed: 1, requests: 2 });
    // a failed chunk is not fetched again until retryFailed
    fetcher.want(0, [4]);
    expect(store.live()).toEqual([]);
    fetcher.retryFailed();
    fetcher.want(0, [4, 5]);
    store.fail(5, new StoreError('missing-chunk', 'missing'));
    store.answer(4);
    await fetcher.idle();
    expect(errors).toEqual(['4:http', '5:missing-chunk']);
  });

  it('throughput is bytes over the time with requests in flight', async () => {
    const { store, fetcher, tick } = setup();
    fetcher.want(0, [999]); // 1000 bytes
    tick(500);
    store.answer(999);
    await fetcher.idle();
    tick(10_000); // idle time does not count
    expect(fetcher.counters.throughputBytesPerSecond).toBe(2000);
  });
});
