// Chunk ranges learnt as chunks arrive (issue 37): for a store without range
// arrays (lossless chunks with no sidecar, zfp stores written by others),
// each resident chunk's [min, max] of the values the surface is made from,
// as the GPU decoded them at the store's rate, is recorded once a surface
// over its pool has been computed. The plan then treats a chunk as a range
// array would (plan.ts: needed iff lo < iso <= hi over its 27-chunk
// neighbourhood), with an unknown chunk anywhere in the neighbourhood
// making it needed: so a later isovalue or camera neither fetches nor keeps
// a chunk known to hold no surface, and never misses one that may.
//
// Kept per opened store for the session; bounded: a level's ranges are an
// array of 2 f32 per chunk, made when its first range arrives, for levels
// of at most MAX_LEARNT_CHUNKS chunks (the finer levels of a vast store are
// not learnt: their chunks stay needed, as before).
import { neighbourhoodOf, rangeNeeded } from './plan.ts';
import type { ChunkIndex } from './types.ts';

/** The most chunks a level may have for its ranges to be learnt (2 f32 each: 32 MiB at most). */
export const MAX_LEARNT_CHUNKS = 2 ** 22;

type Grid = readonly [number, number, number];

export class LearntRanges {
  readonly #levels: (Float32Array | null)[];
  readonly #known: number[];
  #lo = Infinity;
  #hi = -Infinity;

  constructor(readonly grids: readonly Grid[]) {
    this.#levels = grids.map(() => null);
    this.#known = grids.map(() => 0);
  }

  /** Bytes its ranges take (the levels learnt so far). */
  get bytes(): number {
    return this.#levels.reduce((a, r) => a + (r?.byteLength ?? 0), 0);
  }

  /** Whether these are ranges of levels with these chunk grids. */
  fits(grids: readonly Grid[]): boolean {
    return grids.length === this.grids.length && grids.every((g, L) => g.every((n, a) => n === this.grids[L][a]));
  }

  /** Whether level L's ranges can be learnt (not too many chunks). */
  learns(L: number): boolean {
    const g = this.grids[L];
    return g !== undefined && g[0] * g[1] * g[2] <= MAX_LEARNT_CHUNKS;
  }

  /** Chunks of level L whose range is known. */
  knownCount(L: number): number {
    return this.#known[L] ?? 0;
  }

  /** Whether chunk c of level L has a learnt range. */
  has(L: number, c: ChunkIndex): boolean {
    const r = this.#levels[L];
    return r !== null && r !== undefined && !Number.isNaN(r[2 * c]);
  }

  /** [min, max] of chunk c of level L, or null while unknown. */
  get(L: number, c: ChunkIndex): [number, number] | null {
    if (!this.has(L, c)) return null;
    const r = this.#levels[L]!;
    return [r[2 * c], r[2 * c + 1]];
  }

  /** Records chunk c's range (min > max: no finite value); a level that is not learnt ignores it. */
  record(L: number, c: ChunkIndex, lo: number, hi: number): void {
    if (!this.learns(L) || Number.isNaN(lo) || Number.isNaN(hi)) return;
    const g = this.grids[L];
    if (!Number.isInteger(c) || c < 0 || c >= g[0] * g[1] * g[2]) throw new RangeError(`LearntRanges: chunk ${c} outside level ${L}`);
    let r = this.#levels[L];
    if (!r) {
      r = new Float32Array(2 * g[0] * g[1] * g[2]).fill(Number.NaN);
      this.#levels[L] = r;
    }
    if (Number.isNaN(r[2 * c])) this.#known[L]++;
    r[2 * c] = lo;
    r[2 * c + 1] = hi;
    if (lo <= hi) {
      this.#lo = Math.min(this.#lo, lo);
      this.#hi = Math.max(this.#hi, hi);
    }
  }

  /**
   * Whether the surface at `iso` needs chunk c of level L: plan.ts's rule
   * over the chunk and its 26 neighbours, true while any of them is unknown.
   * Reads only those 27 entries (neighbourhoodOf): nothing is made per level.
   */
  needs(L: number, iso: number, c: ChunkIndex): boolean {
    const r = this.#levels[L];
    if (!r) return true;
    const [lo, hi] = neighbourhoodOf(this.grids[L], r, c);
    return rangeNeeded(lo, hi, iso);
  }

  /** Level L's ranges as a range array would hold them ([min, max] per chunk, NaN where unknown), or null if none is known. */
  level(L: number): Float32Array | null {
    return this.#levels[L] ?? null;
  }

  /** [min, max] over every learnt range of every level, or null when none is finite. */
  valueRange(): [number, number] | null {
    return this.#lo <= this.#hi ? [this.#lo, this.#hi] : null;
  }
}

/** Slots whose ranges are read back at once (8 bytes each: reduced per slot on the GPU, Isosurface.readSlotRanges). */
const LEARN_SLOTS = 4096;

/**
 * Learns the ranges of level L's `chunks` (resident in `volume`) from the
 * block ranges `surface` was last computed with, in batches of at most
 * LEARN_SLOTS slots: each batch only while `valid()` (no chunk put or
 * evicted since that surface was computed, the surface still live), since a
 * slot's block ranges are its chunk's only then. Both stream engines call it.
 */
export async function learnSlotRanges(
  learnt: LearntRanges,
  L: number,
  chunks: readonly ChunkIndex[],
  volume: { has(c: ChunkIndex): boolean; slotOfChunk(c: ChunkIndex): number | undefined; readonly blocksPerChunk: number },
  surface: { readSlotRanges?(slots: readonly number[]): Promise<Float32Array> },
  valid: () => boolean,
): Promise<void> {
  if (!surface.readSlotRanges || !learnt.learns(L)) return;
  const todo = chunks.filter((c) => !learnt.has(L, c));
  const batch = LEARN_SLOTS;
  for (let i = 0; i < todo.length; i += batch) {
    if (!valid()) return;
    const part = todo.slice(i, i + batch).filter((c) => volume.has(c));
    // the copies are submitted by this call, while the surface's buffers live; the wait may outlast them
    const r = await surface.readSlotRanges(part.map((c) => volume.slotOfChunk(c)!)).catch(() => null);
    if (!r) return;
    part.forEach((c, k) => learnt.record(L, c, r[2 * k], r[2 * k + 1]));
  }
}

/**
 * The ranges learnt for a store in this session, by a key naming the store
 * and what its values are (the source it was opened from, rate, time point, channel): a store opened
 * again (a new rate and back, the refinement switched) keeps what it learnt.
 * Bounded in bytes (SESSION_RANGES_BYTES), least recently opened let go
 * first, the last STORES_KEPT always kept: every time point of a series
 * keeps its own (a second pass over the series neither fetches nor keeps a
 * chunk a first pass found without surface).
 */
export function sessionRanges(key: string, grids: readonly Grid[]): LearntRanges {
  const kept = session.get(key);
  session.delete(key);
  const r = kept?.fits(grids) ? kept : new LearntRanges(grids);
  session.set(key, r);
  let bytes = 0;
  for (const v of session.values()) bytes += v.bytes;
  for (const [k, v] of session) {
    if (session.size <= STORES_KEPT || bytes <= SESSION_RANGES_BYTES) break;
    session.delete(k);
    bytes -= v.bytes;
  }
  return r;
}

/** Stores whose learnt ranges are kept whatever their bytes. */
const STORES_KEPT = 4;
/** Bytes of learnt ranges kept in a session beyond those (a 2048^3 store's level 0 in 64^3 chunks: 256 KiB a time point). */
export const SESSION_RANGES_BYTES = 64 * 2 ** 20;
const session = new Map<string, LearntRanges>();
