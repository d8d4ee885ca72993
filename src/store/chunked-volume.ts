// The GPU side of a chunked zfp store level: a pool of compressed chunks (a
// zfp stream with its header per chunk, all of one size at a fixed rate),
// a page table chunk -> pool slot (0xffffffff = not resident), and the
// block addressing the decoder needs to decode a block straight from its
// pooled chunk (shaders/store/chunk_blocks.wgsl). An Isosurface reads through
// it (Isosurface.create(gpu, chunkedVolume, options)): put/evict only queue
// writes and note the chunk; before its next surface the Isosurface calls
// encodeSync, which recomputes on the GPU the block ranges of the changed
// chunks, the neighbourhood ranges and group (= chunk) ranges of those
// chunks and their 26 neighbours, and drops their blocks from the block
// cache. Non-resident chunks' blocks get empty ranges: never active.
import type { GpuContext } from '../gpu/device.ts';
import { dispatchLinear } from '../gpu/dispatch.ts';
import { composeWgsl, type WgslPart } from '../gpu/wgsl.ts';
import type { ChunkSyncTargets, ChunkedBlockSource } from '../isosurface/source.ts';
import { decodeBlocksListLayout, type ZfpBlockSource } from '../zfp/decoder.ts';
import { bitsPerBlockForRate, openZfpStream, planZfpStream } from '../zfp/format.ts';
import { maxShardBytesFor } from '../zfp/gpu-stream.ts';
import { objectId } from '../zfp/gpu-util.ts';
import { ChunkError } from './chunk-error.ts';
import { chunkWgsl } from './chunk-wgsl.ts';
import type { ChunkIndex, ChunkLevelLayout } from './types.ts';

export { ChunkError } from './chunk-error.ts';

const NONE = 0xffffffff;
const CHUNK_PARAMS_BYTES = 64;
const STREAM_PARAMS_BYTES = 48;

type Kind = 'uniform' | 'read' | 'rw';

function layoutOf(device: GPUDevice, label: string, entries: [number, Kind][]): GPUBindGroupLayout {
  return device.createBindGroupLayout({
    label,
    entries: entries.map(([binding, kind]) => ({
      binding,
      visibility: GPUShaderStage.COMPUTE,
      buffer: { type: kind === 'uniform' ? 'uniform' : kind === 'read' ? 'read-only-storage' : 'storage' },
    })),
  });
}

function pipelineOf(device: GPUDevice, label: string, parts: WgslPart[], entryPoint: string, layouts: GPUBindGroupLayout[]): GPUComputePipeline {
  const module = device.createShaderModule({ label, code: composeWgsl(...parts) });
  return device.createComputePipeline({ label, layout: device.createPipelineLayout({ label, bindGroupLayouts: layouts }), compute: { module, entryPoint } });
}

export class ChunkedVolume implements ChunkedBlockSource {
  readonly kind = 'chunked' as const;
  readonly info: ChunkedBlockSource['info'];
  readonly groupEdgeBlocks: number;
  readonly poolBytes: number;
  readonly blocks: ZfpBlockSource;
  readonly chunkCount: number;
  private readonly pool: GPUBuffer;
  private readonly pageTable: GPUBuffer;
  private readonly streamParams: GPUBuffer;
  private readonly chunkParams: GPUBuffer;
  private readonly updateList: GPUBuffer;
  private readonly slotOf: Uint32Array;
  private readonly freeSlots: number[] = [];
  private readonly changed = new Set<ChunkIndex>();
  private readonly word = new Uint32Array(1);
  private readonly paramWords = new Uint32Array(CHUNK_PARAMS_BYTES / 4);
  private readonly bitsPerBlock: number;
  private readonly headerBits: number;
  private readonly rangesPipeline: GPUComputePipeline;
  private readonly neighbourhoodPipeline: GPUComputePipeline;
  private readonly groupRangePipeline: GPUComputePipeline;
  private readonly poolGroup: GPUBindGroup;
  private readonly tableGroup: GPUBindGroup;
  private readonly rangesLayout: GPUBindGroupLayout;
  private readonly neighbourhoodLayout: GPUBindGroupLayout;
  private readonly groupRangeLayout: GPUBindGroupLayout;
  private syncGroups?: { key: string; ranges: GPUBindGroup; neighbourhood: GPUBindGroup; groupRange: GPUBindGroup };
  private resident = 0;
  private attached = false;
  private destroyed = false;

  private constructor(
    private readonly gpu: GpuContext,
    readonly layout: ChunkLevelLayout,
    readonly poolChunks: number,
  ) {
    const { device } = gpu;
    const [nx, ny, nz] = layout.dims;
    const C = layout.chunkEdge;
    const e = C / 4;
    const blockGrid: [number, number, number] = [Math.ceil(nx / 4), Math.ceil(ny / 4), Math.ceil(nz / 4)];
    const [gx, gy, gz] = layout.chunkGrid;
    this.chunkCount = gx * gy * gz;
    this.groupEdgeBlocks = e;
    this.info = { fileName: layout.name, dims: [nx, ny, nz], blockGrid, blockCount: blockGrid[0] * blockGrid[1] * blockGrid[2] };
    const plan = planZfpStream(layout.name, [C, C, C], layout.rate, true);
    this.bitsPerBlock = plan.bitsPerBlock;
    this.headerBits = plan.payloadBitOffset;
    this.slotOf = new Uint32Array(this.chunkCount).fill(NONE);
    for (let s = poolChunks - 1; s >= 0; s--) this.freeSlots.push(s);

    const storage = GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST | GPUBufferUsage.COPY_SRC;
    // One extra zero word: the bit reader looks one word ahead.
    this.pool = device.createBuffer({ label: `ChunkedVolume.pool (${layout.name})`, size: poolChunks * layout.chunkBytes + 4, usage: storage });
    this.pageTable = device.createBuffer({ label: 'ChunkedVolume.pageTable', size: this.chunkCount * 4, usage: storage, mappedAtCreation: true });
    new Uint32Array(this.pageTable.getMappedRange()).fill(NONE);
    this.pageTable.unmap();
    this.streamParams = device.createBuffer({ label: 'ChunkedVolume.streamParams', size: STREAM_PARAMS_BYTES, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
    device.queue.writeBuffer(this.streamParams, 0, new Uint32Array([nx, ny, nz, this.bitsPerBlock, ...blockGrid, this.info.blockCount, 0, this.info.blockCount, this.headerBits, 0]));
    this.chunkParams = device.createBuffer({ label: 'ChunkedVolume.chunkParams', size: CHUNK_PARAMS_BYTES, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
    this.paramWords.set([...blockGrid, this.info.blockCount, gx, gy, gz, e, layout.chunkBytes / 4, this.headerBits, e ** 3, 0, 0, 0, 0, 0]);
    device.queue.writeBuffer(this.chunkParams, 0, this.paramWords);
    // The changed chunks, then the dilated ones: at most 2 x chunks entries.
    this.updateList = device.createBuffer({ label: 'ChunkedVolume.updateList', size: 8 * this.chunkCount, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST });
    this.poolBytes = this.pool.size + this.pageTable.size + this.updateList.size + this.streamParams.size + this.chunkParams.size;

    const poolLayout = layoutOf(device, 'ChunkedVolume.pool.layout', [[0, 'read'], [1, 'uniform'], [2, 'read'], [3, 'uniform']]);
    const tableLayout = layoutOf(device, 'ChunkedVolume.table.layout', [[2, 'read'], [3, 'uniform']]);
    this.rangesLayout = layoutOf(device, 'ChunkedVolume.ranges.layout', [[0, 'read'], [1, 'rw'], [2, 'rw'], [3, 'rw'], [4, 'rw'], [5, 'rw']]);
    this.neighbourhoodLayout = layoutOf(device, 'ChunkedVolume.neighbourhood.layout', [[0, 'read'], [1, 'read'], [2, 'rw']]);
    this.groupRangeLayout = layoutOf(device, 'ChunkedVolume.groupRange.layout', [[0, 'read'], [3, 'read'], [4, 'rw']]);
    const decodeBlocksPipeline = pipelineOf(device, 'ChunkedVolume.decodeBlocks', chunkWgsl.decodeBlocks, 'decode_blocks', [poolLayout, decodeBlocksListLayout(device)]);
    this.rangesPipeline = pipelineOf(device, 'ChunkedVolume.blockRanges', chunkWgsl.blockRanges, 'chunk_block_ranges', [poolLayout, this.rangesLayout]);
    this.neighbourhoodPipeline = pipelineOf(device, 'ChunkedVolume.neighbourhood', chunkWgsl.neighbourhood, 'chunk_neighbourhood', [tableLayout, this.neighbourhoodLayout]);
    this.groupRangePipeline = pipelineOf(device, 'ChunkedVolume.groupRange', chunkWgsl.neighbourhood, 'chunk_group_range', [tableLayout, this.groupRangeLayout]);
    const entries = (list: [number, GPUBuffer][]) => list.map(([binding, buffer]) => ({ binding, resource: { buffer } }));
    this.poolGroup = device.createBindGroup({
      label: 'ChunkedVolume.pool.bindGroup',
      layout: poolLayout,
      entries: entries([[0, this.pool], [1, this.streamParams], [2, this.pageTable], [3, this.chunkParams]]),
    });
    this.tableGroup = device.createBindGroup({ label: 'ChunkedVolume.table.bindGroup', layout: tableLayout, entries: entries([[2, this.pageTable], [3, this.chunkParams]]) });
    const self = this;
    this.blocks = {
      device,
      get isDestroyed() {
        return self.destroyed;
      },
      info: { fileName: layout.name },
      shards: [{ bindGroup: this.poolGroup }],
      decodeBlocksPipeline,
    };
  }

  /**
   * A pool of `poolChunks` chunks of `layout` on the GPU. Throws a RangeError
   * naming the level if the layout is inconsistent (chunk bytes not those of
   * a C^3 zfp stream with header at the rate) or the pool does not fit one
   * storage binding (the cap: min(maxStorageBufferBindingSize, maxBufferSize)).
   */
  static create(gpu: GpuContext, layout: ChunkLevelLayout, opts: { poolChunks: number }): ChunkedVolume {
    const { name, dims, chunkEdge: C, chunkGrid, rate, chunkBytes } = layout;
    const fail = (why: string): never => {
      throw new RangeError(`${name}: ${why}`);
    };
    if (!dims.every((n) => Number.isInteger(n) && n > 0)) fail(`dimensions ${dims.join('x')} are not positive integers`);
    if (!(Number.isInteger(C) && C >= 4 && C % 4 === 0)) fail(`the chunk edge ${C} is not a positive multiple of 4`);
    if (!dims.every((n, k) => chunkGrid[k] === Math.ceil(n / C))) fail(`the chunk grid ${chunkGrid.join('x')} is not ceil(${dims.join('x')} / ${C})`);
    const plan = planZfpStream(name, [C, C, C], rate, true);
    if (plan.bitsPerBlock !== bitsPerBlockForRate(rate)) fail(`rate ${rate} is not a fixed rate zfp writes`);
    if (chunkBytes !== plan.paddedBytes) fail(`a ${C}^3 chunk at rate ${rate} is ${plan.paddedBytes} bytes as zfpy writes it (with header), not ${chunkBytes}`);
    const blocks = Math.ceil(dims[0] / 4) * Math.ceil(dims[1] / 4) * Math.ceil(dims[2] / 4);
    if (blocks > 0xffffffff) fail(`${blocks} blocks are more than 2^32 - 1`);
    const n = opts.poolChunks;
    if (!(Number.isInteger(n) && n >= 1)) fail(`poolChunks must be a positive integer (got ${n})`);
    const max = maxShardBytesFor(gpu.device);
    const maxChunks = Math.floor((max - 4) / chunkBytes);
    if (n > maxChunks) {
      fail(`a pool of ${n} chunks (${n * chunkBytes} bytes) does not fit one storage binding of this device (${max} bytes): at most ${maxChunks} chunks of ${chunkBytes} bytes`);
    }
    return new ChunkedVolume(gpu, layout, n);
  }

  /** Chunks of this layout one pool may hold on this device (one storage binding). */
  static maxPoolChunks(gpu: GpuContext, layout: Pick<ChunkLevelLayout, 'chunkBytes'>): number {
    return Math.floor((maxShardBytesFor(gpu.device) - 4) / layout.chunkBytes);
  }

  get residentCount(): number {
    return this.resident;
  }

  has(chunk: ChunkIndex): boolean {
    return this.inRange(chunk) && this.slotOf[chunk] !== NONE;
  }

  /** The chunk's (x, y, z) in the chunk grid. */
  chunkCoords(chunk: ChunkIndex): [number, number, number] {
    const [gx, gy] = this.layout.chunkGrid;
    return [chunk % gx, Math.floor(chunk / gx) % gy, Math.floor(chunk / (gx * gy))];
  }

  private inRange(chunk: ChunkIndex): boolean {
    return Number.isInteger(chunk) && chunk >= 0 && chunk < this.chunkCount;
  }

  private error(chunk: ChunkIndex, why: string): ChunkError {
    const xyz = this.inRange(chunk) ? this.chunkCoords(chunk) : ([NaN, NaN, NaN] as [number, number, number]);
    const where = this.inRange(chunk) ? `chunk (${xyz.join(', ')})` : `chunk ${chunk}`;
    return new ChunkError(`${this.layout.name} ${where}: ${why}`, this.layout.name, xyz);
  }

  /**
   * Copies the chunk's stored bytes into a free pool slot (queue.writeBuffer);
   * its blocks' ranges are computed on the GPU before the next surface. A
   * resident chunk is overwritten in place. Throws a ChunkError (the volume
   * stays as it was) if the bytes are not a zfp fixed-rate stream of this
   * layout, or if the pool is full.
   */
  put(chunk: ChunkIndex, bytes: Uint8Array): void {
    if (this.destroyed) throw new Error(`${this.layout.name}: the chunked volume was destroyed`);
    if (!this.inRange(chunk)) throw this.error(chunk, `not a chunk of the ${this.layout.chunkGrid.join('x')} grid`);
    const { chunkEdge: C, chunkBytes, rate } = this.layout;
    let info;
    try {
      info = openZfpStream(bytes, `${this.layout.name} chunk (${this.chunkCoords(chunk).join(', ')})`);
    } catch (e) {
      throw this.error(chunk, `not a zfp stream of this level: ${e instanceof Error ? e.message : String(e)}`);
    }
    if (!info.hasHeader) throw this.error(chunk, 'the chunk has no zfp header (numcodecs zfpy writes one)');
    if (info.dims.some((n) => n !== C)) throw this.error(chunk, `the chunk is ${info.dims.join('x')} voxels, the level's chunks are ${C}^3`);
    if (info.bitsPerBlock !== this.bitsPerBlock) throw this.error(chunk, `the chunk is ${info.mode}, the level's rate is ${rate} (${this.bitsPerBlock} bits per block)`);
    if (bytes.byteLength !== chunkBytes) throw this.error(chunk, `the chunk has ${bytes.byteLength} bytes, the level's chunks have ${chunkBytes}`);
    let slot = this.slotOf[chunk];
    if (slot === NONE) {
      const free = this.freeSlots.pop();
      if (free === undefined) throw this.error(chunk, `the chunk pool is full (${this.poolChunks} chunks); evict one first`);
      slot = free;
      this.resident++;
    }
    const { queue } = this.gpu.device;
    queue.writeBuffer(this.pool, slot * chunkBytes, bytes.buffer, bytes.byteOffset, chunkBytes);
    this.slotOf[chunk] = slot;
    this.word[0] = slot;
    queue.writeBuffer(this.pageTable, chunk * 4, this.word);
    this.changed.add(chunk);
  }

  /** Frees the chunk's slot (nothing if it is not resident); its blocks leave the block cache and become inactive before the next surface. */
  evict(chunk: ChunkIndex): void {
    if (this.destroyed || !this.has(chunk)) return;
    this.freeSlots.push(this.slotOf[chunk]);
    this.slotOf[chunk] = NONE;
    this.resident--;
    this.word[0] = NONE;
    this.gpu.device.queue.writeBuffer(this.pageTable, chunk * 4, this.word);
    this.changed.add(chunk);
  }

  /** The resident chunks (ascending). */
  residentChunks(): ChunkIndex[] {
    const out: ChunkIndex[] = [];
    for (let c = 0; c < this.chunkCount; c++) if (this.slotOf[c] !== NONE) out.push(c);
    return out;
  }

  attach(): void {
    if (this.attached) throw new Error(`${this.layout.name}: the chunked volume already feeds an Isosurface (one per volume)`);
    this.attached = true;
    for (const c of this.residentChunks()) this.changed.add(c);
  }

  /** Chunks changed since the last sync (put or evicted). */
  get changedCount(): number {
    return this.changed.size;
  }

  encodeSync(encoder: GPUCommandEncoder, t: ChunkSyncTargets): void {
    if (this.changed.size === 0) return;
    const { device } = this.gpu;
    const [gx, gy, gz] = this.layout.chunkGrid;
    const changed = [...this.changed];
    this.changed.clear();
    const dilated = new Set<number>();
    for (const c of changed) {
      const [x, y, z] = this.chunkCoords(c);
      for (let k = Math.max(0, z - 1); k <= Math.min(gz - 1, z + 1); k++)
        for (let j = Math.max(0, y - 1); j <= Math.min(gy - 1, y + 1); j++)
          for (let i = Math.max(0, x - 1); i <= Math.min(gx - 1, x + 1); i++) dilated.add(i + gx * (j + gy * k));
    }
    const list = new Uint32Array(changed.length + dilated.size);
    list.set(changed);
    list.set([...dilated], changed.length);
    device.queue.writeBuffer(this.updateList, 0, list);
    this.paramWords[11] = changed.length;
    this.paramWords[12] = dilated.size;
    device.queue.writeBuffer(this.chunkParams, 0, this.paramWords);

    const groups = this.bindSync(t);
    const perChunk = this.groupEdgeBlocks ** 3;
    const pass = encoder.beginComputePass({ label: 'ChunkedVolume.sync' });
    pass.setPipeline(this.rangesPipeline);
    pass.setBindGroup(0, this.poolGroup);
    pass.setBindGroup(1, groups.ranges);
    dispatchLinear(pass, Math.ceil((changed.length * perChunk) / 64), device.limits.maxComputeWorkgroupsPerDimension);
    pass.setPipeline(this.neighbourhoodPipeline);
    pass.setBindGroup(0, this.tableGroup);
    pass.setBindGroup(1, groups.neighbourhood);
    dispatchLinear(pass, Math.ceil((dilated.size * perChunk) / 64), device.limits.maxComputeWorkgroupsPerDimension);
    pass.setPipeline(this.groupRangePipeline);
    pass.setBindGroup(1, groups.groupRange);
    dispatchLinear(pass, Math.ceil(dilated.size / 64), device.limits.maxComputeWorkgroupsPerDimension);
    pass.end();
  }

  /** Bind groups of the sync over the Isosurface's buffers (rebuilt only when one of them was replaced, e.g. cache growth). */
  private bindSync(t: ChunkSyncTargets) {
    const key = [t.blockRanges, t.neighbourhoodRanges, t.groupRanges, t.blockToSlot, t.slotToBlock, t.slotAge, t.counters].map(objectId).join('|');
    if (this.syncGroups?.key === key) return this.syncGroups;
    const { device } = this.gpu;
    const entries = (list: [number, GPUBuffer][]) => list.map(([binding, buffer]) => ({ binding, resource: { buffer } }));
    this.syncGroups = {
      key,
      ranges: device.createBindGroup({
        label: 'ChunkedVolume.ranges.bindGroup',
        layout: this.rangesLayout,
        entries: entries([[0, this.updateList], [1, t.blockRanges], [2, t.blockToSlot], [3, t.slotToBlock], [4, t.slotAge], [5, t.counters]]),
      }),
      neighbourhood: device.createBindGroup({
        label: 'ChunkedVolume.neighbourhood.bindGroup',
        layout: this.neighbourhoodLayout,
        entries: entries([[0, this.updateList], [1, t.blockRanges], [2, t.neighbourhoodRanges]]),
      }),
      groupRange: device.createBindGroup({
        label: 'ChunkedVolume.groupRange.bindGroup',
        layout: this.groupRangeLayout,
        entries: entries([[0, this.updateList], [3, t.neighbourhoodRanges], [4, t.groupRanges]]),
      }),
    };
    return this.syncGroups;
  }

  destroy(): void {
    if (this.destroyed) return;
    this.destroyed = true;
    for (const b of [this.pool, this.pageTable, this.streamParams, this.chunkParams, this.updateList]) b.destroy();
    this.syncGroups = undefined;
  }
}
