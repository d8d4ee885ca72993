// A CPU stand-in for a level's pool of compressed chunks (ChunkedVolume, as
// the store stream sees it: RoleVolume), for the stream's tests: a set of
// resident chunks with their roles, of `poolChunks` slots of the layout's
// chunk bytes; with a meter, the pool's bytes are counted on it while it
// lives (a child of a budget's meter: the page's one budget).
import type { GpuMemoryMeter } from '../../../src/gpu/memory-meter.ts';
import type { RoleVolume } from '../../../src/store/stream/store-stream.ts';
import type { ChunkIndex, ChunkLevelLayout } from '../../../src/store/types.ts';

export class FakePool implements RoleVolume {
  resident = new Set<ChunkIndex>();
  drawn: ReadonlySet<ChunkIndex> | null = null;
  ghosts: ReadonlySet<ChunkIndex> = new Set();
  destroyed = false;
  readonly blocksPerChunk = 64;
  #counted = 0;

  constructor(
    readonly layout: ChunkLevelLayout,
    public poolChunks: number,
    private readonly meter?: GpuMemoryMeter,
  ) {
    this.#count();
  }
  get poolBytes() {
    return this.poolChunks * this.layout.chunkBytes;
  }
  get residentCount() {
    return this.resident.size;
  }
  get freeCount() {
    return this.poolChunks - this.resident.size;
  }
  has(c: ChunkIndex) {
    return this.resident.has(c);
  }
  put(c: ChunkIndex) {
    if (this.resident.size >= this.poolChunks) throw new Error(`${this.layout.name}: pool full`);
    this.resident.add(c);
  }
  evict(c: ChunkIndex) {
    this.resident.delete(c);
  }
  resize(n: number) {
    if (n < this.resident.size) throw new Error('shrinks below the resident chunks');
    this.poolChunks = n;
    this.#count();
  }
  setRoles(drawn: ReadonlySet<ChunkIndex> | null, ghosts: ReadonlySet<ChunkIndex>) {
    this.drawn = drawn && new Set(drawn);
    this.ghosts = new Set(ghosts);
  }
  slotOfChunk() {
    return undefined;
  }
  reserve() {}
  isReserved() {
    return false;
  }
  destroy() {
    this.destroyed = true;
    this.#count();
  }
  /** What the meter counts: the pool's bytes while it lives. */
  #count() {
    if (!this.meter) return;
    if (this.#counted > 0) this.meter.remove(this.#counted);
    this.#counted = this.destroyed ? 0 : this.poolBytes;
    if (this.#counted > 0) this.meter.add(this.#counted);
  }
}
