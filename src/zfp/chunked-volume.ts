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
// Roles (setRoles, view-dependent refinement): a level's surface may be
// drawn in some of its resident chunks only. A 'drawn' chunk's cells make
// triangles; a 'ghost' chunk only lends its voxels to the drawn ones (the
// +x/+y/+z and diagonal neighbours of a drawn chunk, so that the drawn
// chunk's cells on its upper faces are complete, exactly the level's cells):
// its blocks stay active, its cells make no triangles, and only its cells on
// the chunk's three lower faces keep the vertices they own, the only ones a
// drawn neighbour's triangles can use; an 'idle' chunk is kept in the pool
// but unused (never active, its voxels never read). A 'skirt' (setRoles
// with { skirts: true }: every ghost is one) is a ghost whose cells next to
// a drawn chunk also make triangles: for each axis a whose lower neighbour
// G - e_a is drawn, the skirt G's one layer of cells of chunk-local
// coordinate 0 on a (a one-cell overlap of a drawn region into its +side
// neighbour, drawn at another level, that covers the crack between levels);
// it keeps the cases of its layers 0 and 1 on such an axis too, for the
// vertices those cells index. The role rides in the top 2 bits of the
// chunk's slot-table word, chunk | role << 30 (drawn 0, ghost 1, idle 2,
// skirt 3; an empty slot stays 0xffffffff, never a skirt's word as chunk
// indices stay below 2^30 - 1), so the tables keep their 8 bytes per chunk
// and the kernels their bindings
// (shaders/isosurface/blocks_pool.wgsl); a pool that never sets roles
// writes the words it always did. Role changes write only the words that
// change and log no slot change: nothing decoded depends on a role.

import { formatDims } from '../core/naming.ts';
import { bufferLayout } from '../gpu/bindings.ts';
import { planZfpStream } from './format.ts';
import type { ZfpEncoder } from './encoder.ts';
import { openZfpStream, type ZfpStreamInfo } from './format.ts';
import { maxShardBytesFor, type BlockSource } from './gpu-stream.ts';

/** One level of a chunked zfp store, as the GPU side needs it (facts only, no UI wording). */
export interface ChunkLevelLayout {
  /** Voxels of this level, x, y, z (x fastest). */
  dims: [number, number, number];
  /** Chunk edge C in voxels (a multiple of 4; chunks are C^3, edge chunks stored at full size). */
  chunkEdge: number;
  /** ceil(dims / C) per axis, x, y, z. */
  chunkGrid: [number, number, number];
  /** zfp fixed rate in bits per value. */
  rate: number;
  /** Bytes of one chunk as stored: a zfp stream with its header, identical for every chunk. */
  chunkBytes: number;
  /** For messages: the store and level, e.g. "http://host/bonsai.zarr level 1". */
  name: string;
  /**
   * What put() receives: 'zfp' (default) the chunk's stream as stored;
   * 'float32' its C^3 values (x fastest), encoded on the GPU into the slot
   * (stores of lossless chunks, src/store/zarr/source-store.ts). The slot
   * holds the same zfp stream either way (chunkBytes).
   */
  arrivesAs?: 'zfp' | 'float32';
}

/** Chunk index = cx + gx * (cy + gy * cz) with (gx, gy, gz) = chunkGrid. */
export type ChunkIndex = number;

/**
 * What a chunk does for the level's surface (setRoles): 'drawn' its cells
 * make triangles; 'ghost' it lends its voxels (and the vertices its cells on
 * its lower faces own) to drawn neighbours, no triangles; 'idle' resident
 * but unused; 'skirt' a ghost whose cells of chunk-local coordinate 0 on an
 * axis whose lower neighbour is drawn also make triangles (setRoles'
 * `skirts`).
 */
export type ChunkRole = 'drawn' | 'ghost' | 'idle' | 'skirt';

/** A role's code in the top bits of a slot-table word (ROLE_* in shaders/isosurface/common.wgsl). */
export const CHUNK_ROLE_CODES: Readonly<Record<ChunkRole, number>> = { drawn: 0, ghost: 1, idle: 2, skirt: 3 };

/** setRoles' options. */
export interface ChunkRoleOptions {
  /**
   * Every ghost a 'skirt' (default false): a ghost chunk G whose lower
   * neighbour G - e_a on an axis a is drawn also makes the triangles of
   * its cells of chunk-local coordinate 0 on a (the level's own triangles
   * of those cells), a one-cell overlap of the drawn region into its
   * +side neighbour, which is drawn at another level.
   */
  skirts?: boolean;
}
/**
 * Slot-table word = chunk + role code * 2^ROLE_SHIFT: chunk indices stay
 * below 2^30 - 1 (create), so a skirt's word (code 3) is never an empty
 * slot's 0xffffffff.
 */
const ROLE_SHIFT = 30;

/** A chunk that cannot go into the pool (wrong bytes, pool full), or a layout that cannot be pooled. */
export class ChunkError extends Error {
  constructor(
    message: string,
    readonly chunk?: [number, number, number],
  ) {
    super(message);
    this.name = 'ChunkError';
  }
}

const NONE = 0xffffffff;
const STREAM_PARAMS_BYTES = 48;
const POOL_PARAMS_BYTES = 48;
const PARAMS_STRIDE = 256;

/** Bind group layout 0 of the decoder kernels over a pool (pool_address.wgsl; the device's, from the pipeline cache). */
export function poolBindGroupLayout(device: GPUDevice): GPUBindGroupLayout {
  return bufferLayout(device, 'ChunkedVolume.layout', ['read', 'uniform', 'read', 'uniform']);
}

/** One change of a pool: `chunk` arrived in or left `slot`. */
export interface SlotChange {
  slot: number;
  chunk: ChunkIndex;
}

interface PoolShard {
  buffer: GPUBuffer;
  firstSlot: number;
  endSlot: number;
  bindGroup: GPUBindGroup;
  firstBlock: number;
  endBlock: number;
}

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
  private readonly slotOf = new Map<ChunkIndex, number>();
  /** setRoles: the drawn chunks (null: all), and the ghosts. */
  private drawnChunks: ReadonlySet<ChunkIndex> | null = null;
  private ghostChunks: ReadonlySet<ChunkIndex> = new Set();
  /** setRoles: the ghosts are skirts. */
  private skirts = false;
  private freeSlots: number[] = [];
  /** Slots set aside for chunks on their way (reserve()). */
  private readonly reservedSlot = new Map<ChunkIndex, number>();
  /** One change log per reader (each Isosurface over this pool), so a surface created later still sees every resident chunk. */
  private readonly changeLogs = new Set<Map<string, SlotChange>>();
  /** A checksum of the bytes each chunk index was first put with (kept after evictions). */
  private readonly checksums = new Map<ChunkIndex, number>();
  private readonly word = new Uint32Array(1);
  private readonly bitsPerBlock: number;
  private readonly slotsPerShard: number;
  private capacity = 0;
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
    this.bitsPerBlock = planned.bitsPerBlock;
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
    return this.capacity;
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
    if (poolChunks === this.capacity) return;
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
    if (poolChunks < this.capacity) {
      // move the chunks of slots >= poolChunks into free slots below it
      const low = this.freeSlots.filter((sl) => sl < poolChunks).sort((x, y) => y - x);
      let scratch: GPUBuffer | null = null; // a copy within one buffer goes through it (WebGPU copies between two)
      for (const [chunk, slot] of this.slotOf) {
        if (slot < poolChunks) continue;
        const to = low.pop()!;
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
        this.slotOf.set(chunk, to);
        this.writeTables(chunk, to);
        this.writeSlot(slot, NONE);
        this.logChange(slot, chunk);
        this.logChange(to, chunk);
      }
      this.freeSlots = low.sort((x, y) => y - x);
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
      // lowest free slot first (pop takes from the end)
      const added: number[] = [];
      for (let sl = poolChunks - 1; sl >= this.capacity; sl--) added.push(sl);
      this.freeSlots = [...added, ...this.freeSlots];
    }
    device.queue.submit([encoder.finish()]);
    for (const b of retired) b.destroy(); // freed once the copies are done
    this.bind(shards);
    this.capacity = poolChunks;
  }

  /** The parameters (one StreamParams and one PoolParams record per shard) and each shard's bind group. */
  private bind(shards: ReadonlyArray<Omit<PoolShard, 'bindGroup'>>): void {
    const { device } = this;
    const { dims, chunkGrid, chunkBytes, name } = this.layout;
    const { blockGrid, blockCount } = this.info;
    const params = device.createBuffer({
      label: `${name}.poolParams`,
      size: PARAMS_STRIDE * (2 * shards.length - 1) + POOL_PARAMS_BYTES,
      usage: GPUBufferUsage.UNIFORM,
      mappedAtCreation: true,
    });
    const mapped = params.getMappedRange();
    const poolLayout = poolBindGroupLayout(device);
    const made: PoolShard[] = shards.map((shard, i) => {
      // the level's block count is not used by the pool's kernels (blocks are named by pool id): clamped to a u32
      const count = Math.min(blockCount, 0xffffffff);
      new Uint32Array(mapped, 2 * i * PARAMS_STRIDE, STREAM_PARAMS_BYTES / 4).set([
        ...dims,
        this.bitsPerBlock,
        ...blockGrid,
        count,
        0,
        count,
        0,
        0,
      ]);
      new Uint32Array(mapped, (2 * i + 1) * PARAMS_STRIDE, POOL_PARAMS_BYTES / 4).set([
        ...chunkGrid,
        this.chunkBlocks,
        chunkBytes / 4,
        this.headerBits,
        shard.firstSlot,
        shard.endSlot,
        this.chunkCount,
        0,
        0,
        0,
      ]);
      const bindGroup = device.createBindGroup({
        label: `${name}.pool${i}.bindGroup`,
        layout: poolLayout,
        entries: [
          { binding: 0, resource: { buffer: shard.buffer } },
          { binding: 1, resource: { buffer: params, offset: 2 * i * PARAMS_STRIDE, size: STREAM_PARAMS_BYTES } },
          { binding: 2, resource: { buffer: this.tables } },
          { binding: 3, resource: { buffer: params, offset: (2 * i + 1) * PARAMS_STRIDE, size: POOL_PARAMS_BYTES } },
        ],
      });
      return { ...shard, bindGroup };
    });
    params.unmap();
    this.params?.destroy();
    this.params = params;
    this.shards = made;
  }

  /**
   * A pool of `poolChunks` chunks for one level. Throws a ChunkError when the
   * layout is inconsistent (chunk edge, grid, bytes) or a chunk cannot be
   * addressed.
   */
  static create(gpu: { device: GPUDevice }, layout: ChunkLevelLayout, opts: ChunkedVolumeOptions): ChunkedVolume {
    const { dims, chunkEdge: edge, chunkGrid, rate, chunkBytes, name } = layout;
    const fail = (what: string): never => {
      throw new ChunkError(`${name}: ${what}`);
    };
    if (!dims.every((n) => Number.isInteger(n) && n >= 1)) fail(`impossible dimensions ${dims.join('x')}`);
    if (!Number.isInteger(edge) || edge < 4 || edge % 4 !== 0 || edge > 256)
      fail(`the chunk edge ${edge} is not a multiple of 4 between 4 and 256`);
    if (!chunkGrid.every((g, i) => g === Math.ceil(dims[i] / edge)))
      fail(`the chunk grid ${chunkGrid.join('x')} does not cover ${formatDims(dims)} in chunks of ${edge}`);
    let planned;
    try {
      planned = planZfpStream(`${name} chunk`, [edge, edge, edge], rate, true);
    } catch (e) {
      fail((e as Error).message);
    }
    if (chunkBytes !== planned!.paddedBytes)
      fail(`a ${edge}^3 chunk at rate ${rate} is ${planned!.paddedBytes} bytes as zfp writes it, not ${chunkBytes}`);
    if (!Number.isInteger(opts.poolChunks) || opts.poolChunks < 1) fail(`the pool must hold at least one chunk (got ${opts.poolChunks})`);
    // a level may have any number of blocks (2^36 for 16384^3): the pipeline names blocks by pool id
    // the level's tables are one storage binding; a chunk's bit offsets are 32-bit in WGSL
    const chunks = chunkGrid[0] * chunkGrid[1] * chunkGrid[2];
    const binding = Math.min(gpu.device.limits.maxStorageBufferBindingSize, gpu.device.limits.maxBufferSize);
    if (chunks * 8 > binding)
      fail(
        `${chunks} chunks need ${chunks * 8} bytes of tables (chunk -> slot, slot -> chunk), more than one storage binding of this device (${binding} bytes: maxStorageBufferBindingSize); convert with larger chunks`,
      );
    // the slot table keeps a chunk's role in the top 2 bits of its word; one
    // binding (at most 4 GiB) holds fewer than 2^29 chunks, so this never fails.
    // Chunk indices then stay below 2^30 - 1: a skirt's word, chunk + 3 * 2^30,
    // is never NONE (0xffffffff, an empty slot)
    if (chunks >= 2 ** ROLE_SHIFT) fail(`${chunks} chunks: the slot table holds chunk indices below 2^${ROLE_SHIFT}`);
    if (Math.min(opts.poolChunks, chunks) * (edge / 4) ** 3 >= 2 ** 32)
      fail(`a pool of ${opts.poolChunks} chunks of ${edge}^3 has more block ids than 32 bits hold`);
    if (chunkBytes * 8 >= 2 ** 32) fail(`a chunk of ${chunkBytes} bytes is too large to address in 32-bit bit offsets`);
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
    return poolChunks * layout.chunkBytes + 4 * shards + 8 * chunks + PARAMS_STRIDE * (2 * shards - 1) + POOL_PARAMS_BYTES + values;
  }

  /** Same as byteSize (the name the store side uses for budget accounting). */
  get poolBytes(): number {
    return this.byteSize;
  }

  get residentCount(): number {
    return this.slotOf.size;
  }

  get freeCount(): number {
    return this.freeSlots.length;
  }

  get isDestroyed(): boolean {
    return this.destroyed;
  }

  has(chunk: ChunkIndex): boolean {
    return this.slotOf.has(chunk);
  }

  /** The resident chunks (any order). */
  residentChunks(): ChunkIndex[] {
    return [...this.slotOf.keys()];
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
      this.checkStream(bytes, where, at);
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
    this.checksums.set(chunk, sum);
    let slot = this.slotOf.get(chunk);
    if (slot === undefined && this.reservedSlot.has(chunk)) {
      slot = this.reservedSlot.get(chunk)!;
      this.reservedSlot.delete(chunk);
      this.slotOf.set(chunk, slot);
    }
    if (slot === undefined) {
      slot = this.freeSlots.pop();
      if (slot === undefined) throw new ChunkError(`${where}: the pool is full (${this.poolChunks} chunks); evict one first`, at);
      this.slotOf.set(chunk, slot);
    }
    const shard = this.shards.find((s) => slot! >= s.firstSlot && slot! < s.endSlot)!;
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
    this.logChange(slot, chunk);
  }

  /** Throws a ChunkError unless `bytes` are a zfp fixed-rate stream of one chunk of this layout. */
  private checkStream(bytes: Uint8Array, where: string, at: [number, number, number]): void {
    const edge = this.layout.chunkEdge;
    if (bytes.byteLength !== this.layout.chunkBytes) {
      throw new ChunkError(
        `${where}: ${bytes.byteLength} bytes, but a ${edge}^3 chunk at rate ${this.layout.rate} is ${this.layout.chunkBytes} bytes`,
        at,
      );
    }
    let info;
    try {
      info = openZfpStream(bytes, where);
    } catch (e) {
      throw new ChunkError((e as Error).message, at);
    }
    if (
      !info.hasHeader ||
      info.dims.some((n) => n !== edge) ||
      info.bitsPerBlock !== this.info.bitsPerBlock ||
      info.payloadBitOffset !== this.headerBits
    ) {
      throw new ChunkError(
        `${where}: the chunk's zfp header says ${formatDims(info.dims)} at ${info.mode}; the level's chunks are ${edge}^3 at rate ${this.layout.rate}`,
        at,
      );
    }
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
   * Which chunks the surface is drawn in. `drawn` null (the default): every
   * chunk. Otherwise a chunk in `drawn` is drawn, one in `ghosts` (and not
   * in `drawn`) a ghost, any other idle (ChunkRole). Applies to the chunks
   * resident now and to those put later (the sets are copied); the slot-table
   * words of resident chunks whose role changes are written (queue order:
   * the next surface submitted sees them). A drawn chunk's cells on its
   * upper faces are complete when its +x, +y, +z and diagonal neighbours
   * (those of the level) are resident and drawn or ghosts; next to one that
   * is not resident or idle, its cells within two cells of that face make
   * no triangle (their edges' owners would read it).
   *
   * With `options.skirts` every ghost is a 'skirt' instead: its cells of
   * chunk-local coordinate 0 on an axis a whose chunk below on a (G - e_a)
   * is drawn make triangles too (the level's triangles of those cells: the
   * statistics and readBlockTriangles count them, in the skirt's blocks);
   * such a cell is complete when the skirt's +b, +c and diagonal (b, c)
   * neighbours are resident and not idle, as they are when the ghosts are
   * the drawn chunks' neighbours above; next to one that is not, the cell
   * makes no triangle, as a drawn cell. A skirt with no drawn chunk below
   * it is a ghost. Not sticky: each call says.
   */
  setRoles(drawn: ReadonlySet<ChunkIndex> | null, ghosts: ReadonlySet<ChunkIndex>, options: ChunkRoleOptions = {}): void {
    if (this.destroyed) throw new ChunkError(`${this.layout.name}: the chunk pool was destroyed`);
    const before = new Map<ChunkIndex, ChunkRole>();
    for (const chunk of this.slotOf.keys()) before.set(chunk, this.roleOf(chunk));
    this.drawnChunks = drawn ? new Set(drawn) : null;
    this.ghostChunks = drawn ? new Set(ghosts) : new Set();
    this.skirts = options.skirts ?? false;
    for (const [chunk, slot] of this.slotOf) {
      if (this.roleOf(chunk) !== before.get(chunk)) this.writeSlot(slot, chunk);
    }
  }

  /** The role `chunk` has (or will have when put), from the last setRoles. */
  roleOf(chunk: ChunkIndex): ChunkRole {
    if (this.drawnChunks === null || this.drawnChunks.has(chunk)) return 'drawn';
    if (!this.ghostChunks.has(chunk)) return 'idle';
    return this.skirts ? 'skirt' : 'ghost';
  }

  private logChange(slot: number, chunk: ChunkIndex): void {
    for (const log of this.changeLogs) log.set(`${slot}:${chunk}`, { slot, chunk });
  }

  /** Frees the chunk's slot; its blocks become inactive from the next surface on. */
  evict(chunk: ChunkIndex): void {
    const slot = this.slotOf.get(chunk);
    if (slot === undefined || this.destroyed) return;
    this.slotOf.delete(chunk);
    this.freeSlots.push(slot);
    this.writeTables(chunk, NONE);
    this.writeSlot(slot, NONE);
    this.logChange(slot, chunk);
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
    const keep = new Set(chunks);
    for (const [c, s] of this.reservedSlot) {
      if (keep.has(c)) continue;
      this.reservedSlot.delete(c);
      this.freeSlots.push(s);
    }
    this.freeSlots.sort((a, b) => b - a);
    for (const c of chunks) {
      if (this.slotOf.has(c) || this.reservedSlot.has(c)) continue;
      const s = this.freeSlots.pop();
      if (s === undefined) return;
      this.reservedSlot.set(c, s);
    }
  }

  isReserved(chunk: ChunkIndex): boolean {
    return this.reservedSlot.has(chunk);
  }

  /** The slot a resident chunk is in (its blocks' pool ids start at slot * B), or undefined. */
  slotOfChunk(chunk: ChunkIndex): number | undefined {
    return this.slotOf.get(chunk);
  }

  /** Blocks per chunk, B = (C/4)^3: the pool ids of slot s are s * B ... s * B + B - 1. */
  get blocksPerChunk(): number {
    return this.chunkBlocks ** 3;
  }

  /**
   * A reader's view of the changes: `take()` gives the (slot, chunk) pairs
   * put, evicted or moved since its last call (the pipeline recomputes those
   * slots' ranges and forgets what it decoded from them); the first call
   * gives every resident chunk in its slot when the reader was made.
   * `close()` when the reader goes.
   */
  changeLog(): { take(): SlotChange[]; close(): void } {
    const log = new Map<string, SlotChange>();
    for (const [chunk, slot] of this.slotOf) log.set(`${slot}:${chunk}`, { slot, chunk });
    this.changeLogs.add(log);
    return {
      take: () => {
        const out = [...log.values()];
        log.clear();
        return out;
      },
      close: () => {
        this.changeLogs.delete(log);
      },
    };
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
