// Prefetch of a series' next time point (issue 47): while time point k is
// computed and on screen, the store is opened at the next one and the chunks
// its surface will want are fetched (and, for a store of lossless chunks,
// decoded into bricks) into that time point's own fetcher, bounded in bytes
// (a CPU cache: nothing of it is on the GPU). Showing that time point then
// takes the whole of it over (`take`): the opened store, its metered source,
// the fetcher with what arrived and the chunks counted, so its session opens
// with no metadata requests and its stream finds the prefetched chunks in
// the fetcher's cache; nothing is fetched twice. What the next time point
// wants is the stream on screen's own plan with that time point's ranges
// (StoreStream.wantedAhead): its range arrays are read here once and handed
// over with the store, or, for a store without range arrays, the ranges
// learnt there in this session.
//
// One time point ahead at a time: a new `start` lets the one before go (its
// requests aborted, its store closed), as does `cancel`. The chunks are
// asked coarse step first, then nearest first, and only as many as the
// bound holds (a chunk's size is known before it is fetched: a zfp chunk's
// fixed-rate bytes, a brick's decoded values), so a bound too small for the
// next time point fetches its first steps and the rest comes when it is
// shown (`full` says so).
import type { AsyncReadable } from '@zarrita/storage';
import { ChunkFetcher } from '../fetch/chunk-fetcher.ts';
import { chunkNeeded, neighbourhoodRanges } from '../plan.ts';
import { FetchedChunks } from '../fetched-chunks.ts';
import type { ChunkIndex } from '../types.ts';
import type { ZfpStore } from '../zarr/store.ts';
import { MeteredStore } from '../zarr/stores.ts';

/** The default bound on what is held ahead: CPU bytes of the next time point's chunks. */
export const DEFAULT_PREFETCH_BYTES = 256 * 2 ** 20;

/** What a prefetch did, for the page's panel and the tests. */
export interface PrefetchState {
  /** The time point fetched ahead. */
  time: number;
  /** Chunks its plan wants, and of them those asked (what the bound holds). */
  wanted: number;
  asked: number;
  /** Of those asked, the chunks there (arrived or cached), their bytes as fetched, and the bytes the asked ones take. */
  arrived: number;
  bytes: number;
  askedBytes: number;
  /** The bound, bytes, and whether it kept some wanted chunks from being asked. */
  capacityBytes: number;
  full: boolean;
  /** Every asked chunk is there (or failed: it is asked again when shown). */
  done: boolean;
  /** Why it stopped short (the store at that time point could not be opened, a range array not read), or null. */
  error: string | null;
}

/** A time point made ready ahead, taken over by the session that shows it (StoreSessionOptions.prepared). */
export interface PreparedTime {
  time: number;
  /** The store opened at that time point, on `metered` (range arrays already read are kept for its stream). */
  store: ZfpStore;
  metered: MeteredStore;
  fetcher: ChunkFetcher;
  fetched: FetchedChunks;
  state: PrefetchState;
}

export interface PrefetchSpec {
  time: number;
  /** Opens the store at `time` on `metered` (the same options as the time point on screen, time aside). */
  open(metered: MeteredStore): Promise<ZfpStore>;
  /**
   * The chunks that time point wants, most urgent first, given its needs per
   * level and isovalue (null: the plan cannot be made now: no isovalue yet).
   */
  wanted(
    needsAt: (L: number, iso: number) => ((c: ChunkIndex) => boolean) | null,
    store: ZfpStore,
  ): { level: number; chunk: ChunkIndex }[] | null | Promise<{ level: number; chunk: ChunkIndex }[] | null>;
  /** Ranges learnt in this session for that time point's store (a store without range arrays), if any. */
  learnt?(store: ZfpStore): { learns(L: number): boolean; needs(L: number, iso: number, c: ChunkIndex): boolean } | undefined;
  /** The levels whose ranges the plan may read: their range arrays are read before planning. */
  levels: readonly number[];
  /** Bytes held ahead at most (default DEFAULT_PREFETCH_BYTES). */
  capacityBytes?: number;
  /** Requests in flight at most: fewer than the time point on screen's, which fetches at the same time (default 4). */
  maxInFlight?: number;
}

interface Running {
  spec: PrefetchSpec;
  source: AsyncReadable;
  metered: MeteredStore;
  store: ZfpStore | null;
  fetcher: ChunkFetcher | null;
  fetched: FetchedChunks | null;
  state: PrefetchState;
  /** Resolves once the chunks asked are all there (or it stopped). */
  settled: Promise<void>;
  /** Stops listening to the fetcher (taken over or let go). */
  unlisten: (() => void)[];
  cancelled: boolean;
}

export class SeriesPrefetch {
  #running: Running | null = null;
  readonly #listeners = new Set<(s: PrefetchState | null) => void>();

  /** What the prefetch under way (or the last one not yet taken) did; null when none. */
  get state(): PrefetchState | null {
    return this.#running ? { ...this.#running.state } : null;
  }

  /** The time point being fetched ahead, or null. */
  get time(): number | null {
    return this.#running?.spec.time ?? null;
  }

  /** Calls `l` whenever the state changes (a chunk arrived, started, taken, cancelled). */
  onChange(l: (s: PrefetchState | null) => void): () => void {
    this.#listeners.add(l);
    return () => this.#listeners.delete(l);
  }

  /** Fetches time point `spec.time` ahead from `source`; the prefetch before (of another time point) is let go. */
  start(source: AsyncReadable, spec: PrefetchSpec): void {
    const r = this.#running;
    if (r && r.spec.time === spec.time && r.source === source && !r.state.error) return;
    this.cancel();
    const capacityBytes = Math.max(0, spec.capacityBytes ?? DEFAULT_PREFETCH_BYTES);
    const running: Running = {
      spec,
      source,
      metered: new MeteredStore(source),
      store: null,
      fetcher: null,
      fetched: null,
      state: {
        time: spec.time,
        wanted: 0,
        asked: 0,
        arrived: 0,
        bytes: 0,
        askedBytes: 0,
        capacityBytes,
        full: false,
        done: false,
        error: null,
      },
      settled: Promise.resolve(),
      unlisten: [],
      cancelled: false,
    };
    this.#running = running;
    running.settled = this.#run(running).catch((e) => {
      if (running.cancelled) return;
      running.state.error = (e as Error).message;
      // what could not be made ready is made when shown; the store opened for it goes
      running.fetcher?.cancelAll();
      running.store?.close?.();
      running.store = null;
      running.fetcher = null;
    });
    this.#changed();
  }

  /**
   * Time point `t` made ready: waits until what was asked is there, then
   * hands the store, fetcher and counters over (the prefetch forgets them).
   * Null when nothing is fetched ahead for `t` (a prefetch of another time
   * point is let go) or it could not be made ready.
   */
  async take(t: number, source: AsyncReadable): Promise<PreparedTime | null> {
    const r = this.#running;
    if (!r || r.spec.time !== t || r.source !== source) {
      this.cancel();
      return null;
    }
    await r.settled;
    if (this.#running !== r || r.cancelled || !r.store || !r.fetcher || !r.fetched) {
      if (this.#running === r) this.cancel();
      return null;
    }
    this.#running = null;
    for (const u of r.unlisten) u();
    this.#changed();
    return { time: t, store: r.store, metered: r.metered, fetcher: r.fetcher, fetched: r.fetched, state: { ...r.state } };
  }

  /** Lets the prefetch under way go: its requests are aborted and its store closed. */
  cancel(): void {
    const r = this.#running;
    if (!r) return;
    this.#running = null;
    r.cancelled = true;
    for (const u of r.unlisten) u();
    r.fetcher?.cancelAll();
    r.store?.close?.();
    this.#changed();
  }

  async #run(r: Running): Promise<void> {
    const { spec } = r;
    const store = await spec.open(r.metered);
    if (r.cancelled) {
      store.close?.();
      return;
    }
    r.store = store;
    // the range arrays the plan reads, once: kept for the stream of the session that takes the store over
    const ranges = await readRangesAhead(store, spec.levels);
    if (r.cancelled) return;
    const learnt = spec.learnt?.(store);
    const nbs = new Map<number, Float32Array>();
    const needsAt = (L: number, iso: number): ((c: ChunkIndex) => boolean) | null => {
      const lv = store.levels[L];
      if (!lv || lv.unusable) return null;
      const rg = ranges.get(L);
      if (rg) {
        let nb = nbs.get(L);
        if (!nb) nbs.set(L, (nb = neighbourhoodRanges(lv.layout.chunkGrid, rg)));
        return (c) => chunkNeeded(nb, iso, c);
      }
      if (!lv.rangesPath && learnt?.learns(L)) return (c) => learnt.needs(L, iso, c);
      return null;
    };
    const wanted = await spec.wanted(needsAt, store);
    if (r.cancelled) return;
    if (!wanted) throw new Error(`time point ${spec.time}: nothing to plan ahead yet`);
    // as many as the bound holds, in the plan's order
    const asked: { level: number; chunk: ChunkIndex }[] = [];
    let askedBytes = 0;
    for (const w of wanted) {
      const b = chunkBytesOf(store, w.level);
      if (askedBytes + b > r.state.capacityBytes) {
        r.state.full = true;
        break;
      }
      askedBytes += b;
      asked.push(w);
    }
    const fetcher = new ChunkFetcher(store, {
      maxInFlight: spec.maxInFlight ?? 4,
      // the session's cache holds the prefetched chunks and what it fetches later (scrubbing back)
      cacheBytes: Math.max(r.state.capacityBytes, DEFAULT_PREFETCH_BYTES),
    });
    const fetched = new FetchedChunks(store);
    r.fetcher = fetcher;
    r.fetched = fetched;
    r.state.wanted = wanted.length;
    r.state.asked = asked.length;
    r.state.askedBytes = askedBytes;
    const pending = new Set(asked.map(({ level, chunk }) => level * 2 ** 32 + chunk));
    let finish!: () => void;
    const finished = new Promise<void>((resolve) => (finish = resolve));
    const settle = (level: number, chunk: ChunkIndex) => {
      if (!pending.delete(level * 2 ** 32 + chunk)) return;
      if (pending.size === 0) finish();
    };
    r.unlisten.push(
      fetcher.onChunk((level, chunk, bytes, fromCache) => {
        if (r.cancelled) return;
        if (fetched.add(level, chunk, bytes, fromCache)) r.state.bytes += bytes.byteLength;
        if (pending.has(level * 2 ** 32 + chunk)) r.state.arrived++;
        settle(level, chunk);
        this.#changed();
      }),
    );
    // a chunk that failed is asked again by the session that shows the time point (after its cool-down)
    r.unlisten.push(fetcher.onError((level, chunk) => settle(level, chunk)));
    this.#changed();
    if (asked.length > 0) {
      fetcher.wantAll(asked);
      await Promise.race([finished, fetcher.idle()]);
    }
    if (r.cancelled) return;
    r.state.done = true;
    this.#changed();
  }

  #changed(): void {
    const s = this.state;
    for (const l of this.#listeners) l(s);
  }
}

/** Bytes one chunk of level L takes in the fetcher's cache: a zfp chunk's fixed-rate stream, a brick's decoded values. */
function chunkBytesOf(store: ZfpStore, L: number): number {
  const lv = store.levels[L];
  if (store.source) return 4 * lv.layout.chunkEdge ** 3;
  return lv.chunkCount > 0 ? lv.storedBytes / lv.chunkCount : 0;
}

/**
 * Reads the range arrays of `levels` (those that have one) and keeps them
 * on the store: its readRanges gives each once more without a request (the
 * stream of the session that takes the store over reads them there).
 */
async function readRangesAhead(store: ZfpStore, levels: readonly number[]): Promise<Map<number, Float32Array>> {
  const with_ = levels.filter((L) => store.levels[L]?.rangesPath && !store.levels[L].unusable);
  const read = await Promise.all(with_.map((L) => store.readRanges(L)));
  const out = new Map<number, Float32Array>();
  with_.forEach((L, i) => {
    const r = read[i];
    if (r) out.set(L, r);
  });
  const readRanges = store.readRanges.bind(store);
  const kept = new Map(out);
  store.readRanges = (L, options) => {
    const r = kept.get(L);
    if (r) {
      kept.delete(L);
      return Promise.resolve(r);
    }
    return readRanges(L, options);
  };
  return out;
}
