// Which slot of a chunk pool holds which chunk, on the CPU: the slot
// allocator of ChunkedVolume (chunked-volume.ts), apart from its GPU buffers.
// Free slots are handed out lowest first; slots can be set aside for chunks
// on their way (reserve: the plan's order, not the network's, decides where
// a chunk lands, so surfaces come out the same whatever arrived first); a
// shrink says which chunks move where. Each reader of the pool (an
// Isosurface) has a change log of the (slot, chunk) pairs that changed since
// it last looked.

/** A chunk's index in its level (x fastest). */
type ChunkIndex = number;

/** A slot whose chunk changed (put, evicted or moved). */
export interface SlotChange {
  slot: number;
  chunk: ChunkIndex;
}

/** A chunk moved by a shrink: from slot `from` (past the new end) to slot `to`. */
export interface SlotMove {
  chunk: ChunkIndex;
  from: number;
  to: number;
}

export class PoolSlots {
  readonly #slotOf = new Map<ChunkIndex, number>();
  /** Free slots, the lowest last (pop takes it). */
  #free: number[] = [];
  /** Slots set aside for chunks on their way (reserve()). */
  readonly #reserved = new Map<ChunkIndex, number>();
  /** One change log per reader, so a reader made later still sees every resident chunk. */
  readonly #logs = new Set<Map<string, SlotChange>>();
  #capacity = 0;

  get capacity(): number {
    return this.#capacity;
  }

  get residentCount(): number {
    return this.#slotOf.size;
  }

  get freeCount(): number {
    return this.#free.length;
  }

  has(chunk: ChunkIndex): boolean {
    return this.#slotOf.has(chunk);
  }

  slotOf(chunk: ChunkIndex): number | undefined {
    return this.#slotOf.get(chunk);
  }

  /** The resident chunks and their slots (any order). */
  entries(): IterableIterator<[ChunkIndex, number]> {
    return this.#slotOf.entries();
  }

  resident(): ChunkIndex[] {
    return [...this.#slotOf.keys()];
  }

  /** The slot `chunk` is put into: its own when resident, else the one set aside for it, else the lowest free; undefined when the pool is full. */
  take(chunk: ChunkIndex): number | undefined {
    let slot = this.#slotOf.get(chunk);
    if (slot !== undefined) return slot;
    slot = this.#reserved.get(chunk);
    if (slot !== undefined) this.#reserved.delete(chunk);
    else slot = this.#free.pop();
    if (slot !== undefined) this.#slotOf.set(chunk, slot);
    return slot;
  }

  /** Frees the slot of `chunk`; its slot, or undefined when it was not resident. */
  release(chunk: ChunkIndex): number | undefined {
    const slot = this.#slotOf.get(chunk);
    if (slot === undefined) return undefined;
    this.#slotOf.delete(chunk);
    this.#free.push(slot);
    return slot;
  }

  /**
   * Sets slots aside for `chunks` (in this order, lowest free slot first)
   * that are neither resident nor set aside yet, and gives back those set
   * aside for chunks not in the list.
   */
  reserve(chunks: readonly ChunkIndex[]): void {
    const keep = new Set(chunks);
    for (const [c, s] of this.#reserved) {
      if (keep.has(c)) continue;
      this.#reserved.delete(c);
      this.#free.push(s);
    }
    this.#free.sort((a, b) => b - a);
    for (const c of chunks) {
      if (this.#slotOf.has(c) || this.#reserved.has(c)) continue;
      const s = this.#free.pop();
      if (s === undefined) return;
      this.#reserved.set(c, s);
    }
  }

  isReserved(chunk: ChunkIndex): boolean {
    return this.#reserved.has(chunk);
  }

  /** More slots: `capacity` .. `to - 1` become free (the old free ones, all lower, are still handed out first). */
  grow(to: number): void {
    const added: number[] = [];
    for (let s = to - 1; s >= this.#capacity; s--) added.push(s);
    this.#free = [...added, ...this.#free];
    this.#capacity = to;
  }

  /**
   * Fewer slots: every resident chunk in a slot at or past `to` moves to a
   * free slot below it (the caller copies its bytes). Reservations are given
   * back first. The caller has checked that the resident chunks fit.
   */
  shrink(to: number): SlotMove[] {
    this.reserve([]);
    const low = this.#free.filter((s) => s < to).sort((a, b) => b - a);
    const moves: SlotMove[] = [];
    for (const [chunk, from] of this.#slotOf) {
      if (from < to) continue;
      const slot = low.pop()!;
      moves.push({ chunk, from, to: slot });
      this.#slotOf.set(chunk, slot);
    }
    this.#free = low.sort((a, b) => b - a);
    this.#capacity = to;
    return moves;
  }

  /** Tells every reader that `slot`'s chunk changed. */
  logChange(slot: number, chunk: ChunkIndex): void {
    for (const log of this.#logs) log.set(`${slot}:${chunk}`, { slot, chunk });
  }

  /**
   * A reader's view of the changes: `take()` gives the (slot, chunk) pairs
   * put, evicted or moved since its last call; the first call gives every
   * resident chunk in its slot when the reader was made. `close()` when the
   * reader goes.
   */
  changeLog(): { take(): SlotChange[]; close(): void } {
    const log = new Map<string, SlotChange>();
    for (const [chunk, slot] of this.#slotOf) log.set(`${slot}:${chunk}`, { slot, chunk });
    this.#logs.add(log);
    return {
      take: () => {
        const out = [...log.values()];
        log.clear();
        return out;
      },
      close: () => {
        this.#logs.delete(log);
      },
    };
  }
}
