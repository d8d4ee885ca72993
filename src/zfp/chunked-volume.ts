// One level of a chunked zfp store on the GPU: a pool of compressed chunks
// and a page table (chunk -> pool slot), the block source the isosurface
// pipeline reads when a volume arrives chunk by chunk (src/store/).
//
// Every chunk is a zfp fixed-rate stream of its own, header included, as the
// numcodecs zfpy codec writes it for a C^3 chunk; at a fixed rate all chunks
// of a level have the same size, so the pool is an array of equal slots. Its
// bytes go to the GPU as they are: decoding stays in WGSL
// (shaders/zfp/pool_address.wgsl finds block b in its chunk's slot). zfp
// codes every 4^3 block alone and C is a multiple of 4, so a chunk's blocks
// are exactly those of the whole level compressed as one stream at the same
// rate: a fully resident level gives the in-core pipeline's surface.
//
// The pool is cut into pieces no larger than one storage binding (shards,
// each with its bind group 0 for the decoder kernels). Blocks are named by
// pool id, slot * B + the block's index in its chunk (B = (C/4)^3), so
// everything the isosurface pipeline keeps per block follows the pool's
// capacity, never the level's size (shaders/isosurface/blocks_pool.wgsl).
// The level's tables are one buffer, made with the pool and never resized:
// the page table (chunk -> slot, a word per chunk of the level) and the slot
// table (slot -> chunk, a word per slot a pool of the level can have, which
// is at most its chunk count): 8 bytes per chunk of the level, the only
// per-level state on the GPU (one storage binding, so kernels that use it
// stay within WebGPU's default of 8 per stage). put/evict write the chunk
// and both entries with queue.writeBuffer (ordered after work already
// submitted) and note (slot, chunk) as changed; the isosurface
// pipeline takes the changes before its next surface and recomputes the
// block ranges of just those slots on the GPU and forgets what it had
// decoded from them (changeLog: one per surface, so a surface made later
// starts from every resident chunk).
//
// Roles (setRoles, view-dependent refinement: which resident chunks make
// triangles) are described in chunk-layout.ts; the slot allocator (which
// slot holds which chunk, reservations, change logs) is pool-slots.ts.

import {
  CHUNK_ROLE_CODES,
  ChunkError,
  ChunkRoles,
  type ChunkIndex,
  type ChunkLevelLayout,
  type ChunkRole,
  type ChunkRoleOptions,
  checkChunkLayout,
  checkChunkStream,
  ROLE_SHIFT,
} from './chunk-layout.ts';
import type { ZfpEncoder } from './encoder.ts';
import { planZfpStream, type ZfpStreamInfo } from './format.ts';
import { maxShardBytesFor, type BlockSource } from './gpu-stream.ts';
import { bindPoolShards, type PoolShard, poolParamsBytes } from './pool-shards.ts';
import { PoolSlots, type SlotChange } from './pool-slots.ts';

export { poolBindGroupLayout } from './pool-shards.ts';

export type { SlotChange };
export { CHUNK_ROLE_CODES, ChunkError, type ChunkIndex, type ChunkLevelLayout, type ChunkRole, type ChunkRoleOptions };

const NONE = 0xffffffff;
/** Chunks whose first bytes' checksum is kept (8 MiB or so of Map at most; the store-changed check is for what a session reads again). */
const CHECKSUMS_KEPT = 1 << 20;
export interface ChunkedVolumeOptions {
  /** Pool capacity in chunks. */
  poolChunks: number;
  /** The encoder of chunks that arrive as values (layout.arrivesAs 'float32'), its float32 pipeline ready. */
  encoder?: ZfpEncoder;
  /** Cap on one pool shard (default: the device's binding limit); tests use small values. */
  maxShardBytes?: number;
}

export class ChunkedVolume implements BlockSource {
  readonly addressing = 'pool';
  readonly info: BlockSource['info'];
  /** The pool's pieces; replaced (not mutated) when the pool grows, so readers pick up the new list at their next encode. */
  shards: readonly PoolShard[] = [];
  /** Blocks per chunk edge (C / 4): the pipeline's groups are the chunks. */
  readonly chunkBlocks: number;
  readonly chunkCount: number;
  /** Where block 0 starts inside a chunk's stream (96 or 148 bits). */
  readonly headerBits: number;
  /**
   * The level's tables: words [0, chunkCount) chunk -> slot (NONE: not
   * resident), words [chunkCount, 2 chunkCount) slot -> chunk | role << 30
   * (NONE: empty).
   */
  readonly tables: GPUBuffer;
  private params: GPUBuffer | null = null;
  /** Which slot holds which chunk (the CPU side: pool-slots.ts). */
  private readonly slots = new PoolSlots();
  /** What each chunk does for the surface (setRoles). */
  private readonly roles = new ChunkRoles();
  /** A checksum of the bytes each chunk index was first put with (kept after evictions, the last CHECKSUMS_KEPT chunks). */
  private readonly checksums = new Map<ChunkIndex, number>();
  private readonly word = new Uint32Array(1);
  private readonly slotsPerShard: number;
  private destroyed = false;
  /** Chunks that arrive as values: their stream's plan, the encoder, and one upload buffer reused by every put (queue order keeps them apart). */
  private readonly valuesIn: { info: ZfpStreamInfo; encoder: ZfpEncoder; input: GPUBuffer } | null = null;

  private constructor(
    readonly device: GPUDevice,
    readonly layout: ChunkLevelLayout,
    poolChunks: number,
    maxShardBytes: number,
    encoder?: ZfpEncoder,
  ) {
    const { dims, chunkEdge: edge, chunkGrid, rate, chunkBytes, name } = layout;
    const planned = planZfpStream(`${name} chunk`, [edge, edge, edge], rate, true);
    if (layout.arrivesAs === 'float32') {
      if (!encoder) throw new ChunkError(`${name}: chunks that arrive as values need an encoder`);
      const input = device.createBuffer({
        label: `${name}.chunkValues`,
        size: edge ** 3 * 4,
        usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST,
      });
      this.valuesIn = { info: planned, encoder, input };
    }
    this.chunkBlocks = edge / 4;
    this.headerBits = planned.payloadBitOffset;
    this.chunkCount = chunkGrid[0] * chunkGrid[1] * chunkGrid[2];
    const blockGrid: [number, number, number] = [Math.ceil(dims[0] / 4), Math.ceil(dims[1] / 4), Math.ceil(dims[2] / 4)];
    const blockCount = blockGrid[0] * blockGrid[1] * blockGrid[2];
    this.info = { fileName: name, dims: [...dims], blockGrid, blockCount, bitsPerBlock: planned.bitsPerBlock, rate: planned.rate };
    this.slotsPerShard = Math.floor((maxShardBytes - 4) / chunkBytes);
    if (this.slotsPerShard < 1)
      throw new ChunkError(`${name}: one chunk (${chunkBytes} bytes) does not fit one storage binding of ${maxShardBytes} bytes`);
    this.tables = device.createBuffer({
      label: `${name}.tables`,
      size: 8 * this.chunkCount,
      usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST,
      mappedAtCreation: true,
    });
    new Uint32Array(this.tables.getMappedRange()).fill(NONE);
    this.tables.unmap();
    this.resize(poolChunks);
  }

  /** Chunks the pool holds at most (resize() changes it). */
  get poolChunks(): number {
    return this.slots.capacity;
  }

  /**
   * Sets the capacity to `poolChunks` slots (at least the resident count),
   * resident chunks kept. Growing fills the last shard up to a binding's
   * size (its buffer replaced by a larger copy) and adds shards after it;
   * shrinking first moves the chunks of slots past the end into free slots
   * before it (GPU copies, page table rewritten; the bytes are the same, so
   * nothing decoded goes stale), then cuts the shards. Parameters and bind
   * groups are made again; work already submitted keeps the old buffers
   * alive until it is done.
   */
  resize(poolChunks: number): void {
    if (this.destroyed) throw new ChunkError(`${this.layout.name}: the chunk pool was destroyed`);
    if (!Number.isInteger(poolChunks) || poolChunks < 1 || poolChunks > this.chunkCount)
      throw new ChunkError(`${this.layout.name}: a pool of ${poolChunks} chunks (the level has ${this.chunkCount})`);
    if (poolChunks < this.residentCount)
      throw new ChunkError(`${this.layout.name}: cannot shrink the pool to ${poolChunks} chunks, ${this.residentCount} are resident`);
    if (poolChunks === this.slots.capacity) return;
    this.reserve([]);
    const { device } = this;
    const { chunkBytes, name } = this.layout;
    const encoder = device.createCommandEncoder({ label: `${name}.pool.resize` });
    const retired: GPUBuffer[] = [];
    let shards: Array<Omit<PoolShard, 'bindGroup'>> = this.shards.map(({ bindGroup: _, ...rest }) => rest);
    const shardOf = (slot: number) => shards.find((sh) => slot >= sh.firstSlot && slot < sh.endSlot)!;
    const newBuffer = (index: number, slots: number) =>
      device.createBuffer({
        label: `${name}.pool${index}`,
        // one zero word after the last slot: the bit reader may load the word after a block's last bit
        size: slots * chunkBytes + 4,
        usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST | GPUBufferUsage.COPY_SRC,
      });
    if (poolChunks < this.slots.capacity) {
      // move the chunks of slots >= poolChunks into free slots below it
      let scratch: GPUBuffer | null = null; // a copy within one buffer goes through it (WebGPU copies between two)
      for (const { chunk, from: slot, to } of this.slots.shrink(poolChunks)) {
        const from = shardOf(slot);
        const into = shardOf(to);
        const src = (slot - from.firstSlot) * chunkBytes;
        const dst = (to - into.firstSlot) * chunkBytes;
        if (from.buffer === into.buffer) {
          scratch ??= device.createBuffer({
            label: `${name}.pool.move`,
            size: chunkBytes,
            usage: GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST,
          });
          encoder.copyBufferToBuffer(from.buffer, src, scratch, 0, chunkBytes);
          encoder.copyBufferToBuffer(scratch, 0, into.buffer, dst, chunkBytes);
        } else {
          encoder.copyBufferToBuffer(from.buffer, src, into.buffer, dst, chunkBytes);
        }
        if (scratch && !retired.includes(scratch)) retired.push(scratch);
        this.writeTables(chunk, to);
        this.writeSlot(slot, NONE);
        this.slots.logChange(slot, chunk);
        this.slots.logChange(to, chunk);
      }
      const kept: typeof shards = [];
      for (const sh of shards) {
        if (sh.firstSlot >= poolChunks) retired.push(sh.buffer);
        else if (sh.endSlot <= poolChunks) kept.push(sh);
        else {
          const buffer = newBuffer(kept.length, poolChunks - sh.firstSlot);
          encoder.copyBufferToBuffer(sh.buffer, 0, buffer, 0, (poolChunks - sh.firstSlot) * chunkBytes);
          retired.push(sh.buffer);
          kept.push({ ...sh, buffer, endSlot: poolChunks });
        }
      }
      shards = kept;
    } else {
      const last = shards[shards.length - 1];
      if (last && last.endSlot - last.firstSlot < this.slotsPerShard) {
        const endSlot = Math.min(poolChunks, last.firstSlot + this.slotsPerShard);
        const buffer = newBuffer(shards.length - 1, endSlot - last.firstSlot);
        encoder.copyBufferToBuffer(last.buffer, 0, buffer, 0, last.buffer.size);
        retired.push(last.buffer);
        shards[shards.length - 1] = { ...last, buffer, endSlot };
      }
      for (let first = shards.length ? shards[shards.length - 1].endSlot : 0; first < poolChunks; first += this.slotsPerShard) {
        const endSlot = Math.min(poolChunks, first + this.slotsPerShard);
        shards.push({
          buffer: newBuffer(shards.length, endSlot - first),
          firstSlot: first,
          endSlot,
          firstBlock: 0,
          endBlock: this.info.blockCount,
        });
      }
      this.slots.grow(poolChunks);
    }
    device.queue.submit([encoder.finish()]);
    for (const b of retired) b.destroy(); // freed once the copies are done
    this.bind(shards);
  }

  /** The parameters and each shard's bind group (pool-shards.ts). */
  private bind(shards: ReadonlyArray<Omit<PoolShard, 'bindGroup'>>): void {
    const made = bindPoolShards(this, shards);
    this.params?.destroy();
    this.params = made.params;
    this.shards = made.shards;
  }

  /**
   * A pool of `poolChunks` chunks for one level. Throws a ChunkError when the
   * layout is inconsistent (chunk edge, grid, bytes) or a chunk cannot be
   * addressed.
   */
  static create(gpu: { device: GPUDevice }, layout: ChunkLevelLayout, opts: ChunkedVolumeOptions): ChunkedVolume {
    checkChunkLayout(layout, opts.poolChunks, gpu.device.limits);
    return new ChunkedVolume(gpu.device, layout, opts.poolChunks, opts.maxShardBytes ?? maxShardBytesFor(gpu.device), opts.encoder);
  }

  /**
   * Chunks of this layout one pool may hold on this device: pools are cut
   * into binding-sized shards, so the bound is the page table's 32-bit slot
   * numbers (and, in practice, the memory budget).
   */
  static maxPoolChunks(_gpu: { device: GPUDevice }, _layout: Pick<ChunkLevelLayout, 'chunkBytes'>): number {
    return 2 ** 31;
  }

  /** Bytes of GPU memory held: the pool, the page table and the parameters. */
  get byteSize(): number {
    const values = this.valuesIn?.input.size ?? 0;
    return this.shards.reduce((n, s) => n + s.buffer.size, 0) + this.tables.size + (this.params?.size ?? 0) + values;
  }

  /** Bytes a pool of `poolChunks` chunks of this layout holds (the budget's estimate before one is made). */
  static bytesFor(layout: ChunkLevelLayout, poolChunks: number, maxShardBytes: number): number {
    const perShard = Math.max(1, Math.floor((maxShardBytes - 4) / layout.chunkBytes));
    const shards = Math.max(1, Math.ceil(poolChunks / perShard));
    const chunks = layout.chunkGrid[0] * layout.chunkGrid[1] * layout.chunkGrid[2];
    const values = layout.arrivesAs === 'float32' ? layout.chunkEdge ** 3 * 4 : 0;
    return poolChunks * layout.chunkBytes + 4 * shards + 8 * chunks + poolParamsBytes(shards) + values;
  }

  /** Same as byteSize (the name the store side uses for budget accounting). */
  get poolBytes(): number {
    return this.byteSize;
  }

  get residentCount(): number {
    return this.slots.residentCount;
  }

  get freeCount(): number {
    return this.slots.freeCount;
  }

  get isDestroyed(): boolean {
    return this.destroyed;
  }

  has(chunk: ChunkIndex): boolean {
    return this.slots.has(chunk);
  }

  /** The resident chunks (any order). */
  residentChunks(): ChunkIndex[] {
    return this.slots.resident();
  }

  chunkCoords(chunk: ChunkIndex): [number, number, number] {
    const [gx, gy] = this.layout.chunkGrid;
    return [chunk % gx, Math.floor(chunk / gx) % gy, Math.floor(chunk / (gx * gy))];
  }

  /**
   * Copies a chunk's stored bytes into a free slot. Throws a ChunkError
   * naming the level and the chunk's (x, y, z) when the bytes are not a zfp
   * fixed-rate stream of this layout or the pool is full; the volume stays
   * as it was.
   */
  put(chunk: ChunkIndex, bytes: Uint8Array): void {
    if (this.destroyed) throw new ChunkError(`${this.layout.name}: the chunk pool was destroyed`);
    if (!Number.isInteger(chunk) || chunk < 0 || chunk >= this.chunkCount)
      throw new ChunkError(`${this.layout.name}: there is no chunk ${chunk} (the level has ${this.chunkCount})`);
    const at = this.chunkCoords(chunk);
    const where = `${this.layout.name} chunk (${at.join(', ')})`;
    const edge = this.layout.chunkEdge;
    if (this.valuesIn) {
      if (bytes.byteLength !== edge ** 3 * 4)
        throw new ChunkError(`${where}: ${bytes.byteLength} bytes of values, a ${edge}^3 float32 chunk has ${edge ** 3 * 4}`, at);
    } else {
      checkChunkStream(this.layout, this.info.bitsPerBlock, this.headerBits, bytes, where, at);
    }
    // A store's chunks never change while it is open: different bytes under
    // a chunk index read before mean the store changed, and a surface would
    // mix two versions of it, so they are refused.
    const sum = checksum(bytes);
    const before = this.checksums.get(chunk);
    if (before !== undefined && before !== sum) {
      throw new ChunkError(
        `${where}: its bytes differ from those read before for this chunk; the store changed while it was open: open it again`,
        at,
      );
    }
    const slot = this.slots.take(chunk);
    if (slot === undefined) throw new ChunkError(`${where}: the pool is full (${this.poolChunks} chunks); evict one first`, at);
    if (before === undefined) {
      this.checksums.set(chunk, sum);
      // bounded: a long session over a large level forgets the oldest (Map order) first
      if (this.checksums.size > CHECKSUMS_KEPT) this.checksums.delete(this.checksums.keys().next().value!);
    }
    const shard = this.shards.find((s) => slot >= s.firstSlot && slot < s.endSlot)!;
    const byteOffset = (slot - shard.firstSlot) * this.layout.chunkBytes;
    if (this.valuesIn) {
      const { info, encoder, input } = this.valuesIn;
      this.device.queue.writeBuffer(input, 0, bytes.buffer, bytes.byteOffset, bytes.byteLength);
      const commands = this.device.createCommandEncoder({ label: `${this.layout.name}.encodeChunk` });
      encoder.encodeSlot(commands, { input, dtype: 'float32', info, target: shard.buffer, byteOffset });
      this.device.queue.submit([commands.finish()]);
    } else {
      this.device.queue.writeBuffer(shard.buffer, byteOffset, bytes.buffer, bytes.byteOffset, bytes.byteLength);
    }
    this.writeTables(chunk, slot);
    this.slots.logChange(slot, chunk);
  }

  /** Page-table entry of `chunk` and slot-table entry of `slot` (each NONE to clear). */
  private writeTables(chunk: ChunkIndex, slot: number): void {
    this.word[0] = slot;
    this.device.queue.writeBuffer(this.tables, chunk * 4, this.word);
    if (slot !== NONE) this.writeSlot(slot, chunk);
  }

  /** Slot-table entry of `slot`: `chunk` with its role, or NONE (empty). */
  private writeSlot(slot: number, chunk: ChunkIndex): void {
    this.word[0] = chunk === NONE ? NONE : chunk + CHUNK_ROLE_CODES[this.roleOf(chunk)] * 2 ** ROLE_SHIFT;
    this.device.queue.writeBuffer(this.tables, (this.chunkCount + slot) * 4, this.word);
  }

  /**
   * Which chunks the surface is drawn in (ChunkRoles.set in chunk-layout.ts
   * says how each role draws); the slot-table words of resident chunks whose
   * role changes are written (queue order: the next surface submitted sees
   * them). Not sticky: each call says.
   */
  setRoles(drawn: ReadonlySet<ChunkIndex> | null, ghosts: ReadonlySet<ChunkIndex>, options: ChunkRoleOptions = {}): void {
    if (this.destroyed) throw new ChunkError(`${this.layout.name}: the chunk pool was destroyed`);
    const before = new Map<ChunkIndex, ChunkRole>();
    for (const chunk of this.slots.resident()) before.set(chunk, this.roles.of(chunk));
    this.roles.set(drawn, ghosts, options);
    for (const [chunk, slot] of this.slots.entries()) {
      if (this.roles.of(chunk) !== before.get(chunk)) this.writeSlot(slot, chunk);
    }
  }

  /** The role `chunk` has (or will have when put), from the last setRoles. */
  roleOf(chunk: ChunkIndex): ChunkRole {
    return this.roles.of(chunk);
  }

  /** Frees the chunk's slot; its blocks become inactive from the next surface on. */
  evict(chunk: ChunkIndex): void {
    if (this.destroyed) return;
    const slot = this.slots.release(chunk);
    if (slot === undefined) return;
    this.writeTables(chunk, NONE);
    this.writeSlot(slot, NONE);
    this.slots.logChange(slot, chunk);
  }

  /**
   * Sets slots aside for `chunks` (in this order, lowest free slot first)
   * that are neither resident nor set aside yet, and gives back those set
   * aside for chunks not in the list. So the slot a chunk lands in follows
   * the caller's order (the plan's), not the order chunks arrive in: the
   * same surfaces come out with their vertices in the same order whatever
   * the network did.
   */
  reserve(chunks: readonly ChunkIndex[]): void {
    this.slots.reserve(chunks);
  }

  isReserved(chunk: ChunkIndex): boolean {
    return this.slots.isReserved(chunk);
  }

  /** The slot a resident chunk is in (its blocks' pool ids start at slot * B), or undefined. */
  slotOfChunk(chunk: ChunkIndex): number | undefined {
    return this.slots.slotOf(chunk);
  }

  /** Blocks per chunk, B = (C/4)^3: the pool ids of slot s are s * B ... s * B + B - 1. */
  get blocksPerChunk(): number {
    return this.chunkBlocks ** 3;
  }

  /**
   * A reader's view of the changes (pool-slots.ts): `take()` gives the
   * (slot, chunk) pairs put, evicted or moved since its last call (the
   * pipeline recomputes those slots' ranges and forgets what it decoded from
   * them); the first call gives every resident chunk in its slot when the
   * reader was made. `close()` when the reader goes.
   */
  changeLog(): { take(): SlotChange[]; close(): void } {
    return this.slots.changeLog();
  }

  destroy(): void {
    if (this.destroyed) return;
    this.destroyed = true;
    for (const s of this.shards) s.buffer.destroy();
    this.tables.destroy();
    this.params?.destroy();
    this.valuesIn?.input.destroy();
  }
}

/** FNV-1a over the bytes, 32 bits: tells a chunk's bytes from different ones. */
function checksum(bytes: Uint8Array): number {
  let h = 0x811c9dc5;
  for (let i = 0; i < bytes.length; i++) h = Math.imul(h ^ bytes[i], 0x01000193);
  return h >>> 0;
}
