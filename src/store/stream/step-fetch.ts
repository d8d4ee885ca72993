// The chunks a step of the store stream (store-stream.ts) waits for: slots
// set aside for them in plan order, asked of the fetcher nearest first (what
// the fetcher was still fetching for a superseded step is aborted), each put
// into its level's pool as it arrives, a full pool evicting what neither the
// step nor the step on screen reads. One step waits at a time.
import type { ChunkFetcher } from '../fetch/chunk-fetcher.ts';
import type { ChunkIndex } from '../types.ts';
import type { StreamLevels } from './stream-levels.ts';
import { key, type RoleVolume, type Step, type Waiting } from './stream-types.ts';

export class StepFetch<V extends RoleVolume> {
  #waiting: Waiting | null = null;

  constructor(
    readonly fetcher: ChunkFetcher,
    readonly pools: StreamLevels<V>,
    /** An arrived chunk could not be put into its pool (the stream stops with the reason). */
    readonly onPutFailed: (level: number, e: Error) => void,
  ) {}

  /** Whether the step waiting now waits for this chunk. */
  waitsFor(level: number, chunk: ChunkIndex): boolean {
    return this.#waiting?.missing.has(key(level, chunk)) ?? false;
  }

  /**
   * Fetches the step's `missing` chunks (keys level * 2^32 + chunk, in
   * `order`), keeping resident what the step wants and what is on screen
   * (`shownWanted`); `started` is called once they are asked for. Resolves
   * true once every one arrived, false when the wait was ended (end(): a
   * newer request, a failed chunk, a stop).
   */
  async fetch(
    step: Step,
    missing: Set<number>,
    order: { level: number; chunk: ChunkIndex }[],
    shownWanted: readonly ChunkIndex[][],
    started: () => void,
  ): Promise<boolean> {
    if (missing.size === 0) {
      // everything resident: what a superseded step was still fetching is no longer needed
      this.fetcher.wantAll([]);
      return true;
    }
    const keep = step.wanted.map((w, L) => new Set([...w, ...(shownWanted[L] ?? [])].map((c) => key(L, c))));
    let mine: Waiting | null = null;
    await new Promise<void>((resolve) => {
      this.supersede();
      mine = this.#waiting = { missing, done: resolve, keep };
      this.pools.reserve(step, missing);
      started();
      this.fetcher.wantAll(order);
      if (missing.size === 0) resolve();
    });
    if (this.#waiting === mine) this.#waiting = null;
    return missing.size === 0;
  }

  /** A newer request: the step waiting stops waiting; its requests go on until the next step's replace them. */
  supersede(): void {
    const w = this.#waiting;
    this.#waiting = null;
    w?.done();
  }

  /** Ends the wait (if any): nothing is wanted of the fetcher any more. */
  end(): void {
    const w = this.#waiting;
    this.#waiting = null;
    this.fetcher.wantAll([]);
    w?.done();
  }

  /** A chunk came (from the network or the fetcher's cache): put into its pool if the waiting step wants it. */
  arrived(level: number, chunk: ChunkIndex, bytes: Uint8Array): void {
    const w = this.#waiting;
    const lv = this.pools.levels[level];
    if (!w || !lv?.volume || !w.missing.has(key(level, chunk))) return;
    try {
      this.pools.put(level, chunk, bytes, (c) => w.keep[level]?.has(key(level, c)) ?? false);
    } catch (e) {
      this.onPutFailed(level, e as Error);
      return;
    }
    w.missing.delete(key(level, chunk));
    if (w.missing.size === 0) w.done();
  }
}
