// The distinct chunks that came over for a store session (session.ts), and
// for a series' next time point fetched ahead (series/prefetch.ts), which
// its session then takes over.
import type { ZfpStore } from './zarr/store.ts';

/**
 * The distinct chunks that came over, per level: a bit per chunk, made when
 * a level's first chunk arrives (bounded by the store, not by the session's
 * length). Chunks absent from the store (the fill value) and the fetcher's
 * cache hits are not counted.
 */
export class FetchedChunks {
  readonly #bits: (Uint8Array | undefined)[] = [];
  readonly #count: number[] = [];
  readonly #bytes: number[] = [];
  readonly #listeners: ((level: number, bytes: number) => void)[] = [];

  constructor(private readonly store: ZfpStore) {}

  /** Counts a chunk that arrived; true when it is the first time. */
  add(level: number, chunk: number, bytes: Uint8Array, fromCache: boolean): boolean {
    if (fromCache || this.store.isAbsent(bytes)) return false;
    const bits = (this.#bits[level] ??= new Uint8Array(Math.ceil(this.store.levels[level].chunkCount / 8)));
    const bit = 1 << (chunk & 7);
    if (bits[chunk >>> 3] & bit) return false;
    bits[chunk >>> 3] |= bit;
    this.#count[level] = (this.#count[level] ?? 0) + 1;
    this.#bytes[level] = (this.#bytes[level] ?? 0) + bytes.byteLength;
    for (const l of this.#listeners) l(level, bytes.byteLength);
    return true;
  }

  /** Calls `l` for each chunk counted from now on. */
  onNew(l: (level: number, bytes: number) => void): void {
    this.#listeners.push(l);
  }

  /** Distinct chunks of `level`, or of every level. */
  chunks(level?: number): number {
    return level === undefined ? this.#count.reduce((a, n) => a + (n ?? 0), 0) : (this.#count[level] ?? 0);
  }

  /** Their bytes as they came (compressed chunk bytes). */
  bytes(level?: number): number {
    return level === undefined ? this.#bytes.reduce((a, n) => a + (n ?? 0), 0) : (this.#bytes[level] ?? 0);
  }
}
