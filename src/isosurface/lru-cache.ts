// The GPU-driven LRU block cache (paper Algorithm 1, DESIGN.md steps 2-3):
// slot ages, slot <-> block maps, decoded slot data, and the per-computation
// update recorded from GPU counts only:
//
//   age_slots        every slot ages by one (saturating), all start available
//   mark_cached      active cached blocks: slot age 0, slot unavailable; others are new
//   scan new         -> offsets, n_new
//   plan_update      "exit if n_new = 0": later counts become 0
//   scan available   -> offsets, n_avail
//   compact          new block ids; available slot ids and their ages
//   sort             available slots by age, oldest first (stable radix sort, 16-bit keys)
//   assign_slots     new block i -> i-th oldest available slot, evicting its block
//   decode           the new blocks into their slots (ZfpDecoder.encodeDecodeBlocks)
//
// "Grow if n_new > n_avail" is decided on the GPU before any of this
// (plan_cache: the update fits iff active <= slots); when it does not fit,
// every count above is 0, the cache is left exactly as it was, and the host
// grows the cache when it reads the statistics (see isosurface.ts).
import { dispatchLinear } from '../gpu/dispatch.ts';
import type { StreamCompact, StreamCompactIds } from '../primitives/compact.ts';
import type { ExclusiveScan } from '../primitives/scan.ts';
import { RadixSortByKey } from '../primitives/sort.ts';
import type { ZfpDecoder } from '../zfp/decoder.ts';
import { isChunked, type IsosurfaceSource } from './source.ts';
import { Counters } from './counters.ts';
import { bindGroup, bindGroupLayout, computePipeline, storageBuffer } from './gpu-util.ts';
import { A, AGE_KEY_BITS, SLOT_BYTES } from './layout.ts';
import { isosurfaceWgsl } from './wgsl.ts';

export interface BlockCacheParts {
  stream: IsosurfaceSource;
  decoder: ZfpDecoder;
  counters: Counters;
  /** Sized to the slots (grown with the cache; shared with the block MC, whose counts are per active block <= slots). */
  scan: ExclusiveScan;
  compact: StreamCompact;
  compactIds: StreamCompactIds;
  /** The active list (ActiveBlocks.activeIds). */
  activeIds: GPUBuffer;
  maxWorkgroupsPerDimension: number;
}

/** Bytes per slot of the buffers sized by the capacity (slot data, maps, scratch, sort). */
export const CACHE_BYTES_PER_SLOT = SLOT_BYTES + 4 * (2 + 4 + 3) + 4 * 2 + 1;

interface SlotBuffers {
  capacity: number;
  slotData: GPUBuffer;
  slotAge: GPUBuffer;
  slotToBlock: GPUBuffer;
  availMask: GPUBuffer;
  availOffsets: GPUBuffer;
  availIds: GPUBuffer;
  availAges: GPUBuffer;
  newMask: GPUBuffer;
  newOffsets: GPUBuffer;
  newIds: GPUBuffer;
}

interface Groups {
  age: GPUBindGroup;
  mark: GPUBindGroup;
  assign: GPUBindGroup;
}

interface Pipelines {
  age: GPUComputePipeline;
  mark: GPUComputePipeline;
  assign: GPUComputePipeline;
  fill: GPUComputePipeline;
  ageLayout: GPUBindGroupLayout;
  markLayout: GPUBindGroupLayout;
  assignLayout: GPUBindGroupLayout;
  fillLayout: GPUBindGroupLayout;
}

const FILL_SLOTS = 8;
const FILL_STRIDE = 256;

export class BlockCache {
  /** Per block: its slot, or NONE. */
  readonly blockToSlot: GPUBuffer;
  private slots!: SlotBuffers;
  private groups!: Groups;
  private readonly fillParams: GPUBuffer;
  private fillsRecorded = 0;

  private constructor(
    private readonly device: GPUDevice,
    private readonly parts: BlockCacheParts,
    private readonly pipelines: Pipelines,
    private readonly sort: RadixSortByKey,
    capacity: number,
  ) {
    const blocks = parts.stream.info.blockCount;
    this.blockToSlot = storageBuffer(device, 'Isosurface.blockToSlot', blocks * 4, GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST);
    this.fillParams = device.createBuffer({ label: 'Isosurface.fillParams', size: FILL_SLOTS * FILL_STRIDE, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
    this.slots = this.allocate(capacity);
    this.groups = this.makeGroups();
    this.clear(this.slots.capacity);
  }

  static async create(device: GPUDevice, parts: BlockCacheParts, capacity: number): Promise<BlockCache> {
    const ageLayout = bindGroupLayout(device, 'Isosurface.ageSlots.layout', ['read', 'read', 'rw', 'rw']);
    const markLayout = bindGroupLayout(device, 'Isosurface.markCached.layout', ['read', 'read', 'read', 'rw', 'rw', 'rw']);
    const assignLayout = bindGroupLayout(device, 'Isosurface.assignSlots.layout', ['read', 'read', 'read', 'rw', 'rw', 'rw']);
    const fillLayout = device.createBindGroupLayout({
      label: 'Isosurface.fillNone.layout',
      entries: [
        { binding: 0, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'uniform', hasDynamicOffset: true, minBindingSize: 8 } },
        { binding: 1, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'storage' } },
      ],
    });
    const constants = { MAX_WG_PER_DIM: parts.maxWorkgroupsPerDimension };
    const wgsl = isosurfaceWgsl.lru;
    const [age, mark, assign, fill, sort] = await Promise.all([
      computePipeline(device, 'Isosurface.ageSlots', wgsl, 'age_slots', [ageLayout], constants),
      computePipeline(device, 'Isosurface.markCached', wgsl, 'mark_cached', [markLayout], constants),
      computePipeline(device, 'Isosurface.assignSlots', wgsl, 'assign_slots', [assignLayout], constants),
      computePipeline(device, 'Isosurface.fillNone', wgsl, 'fill_none', [fillLayout], constants),
      RadixSortByKey.create(device, { capacity, maxWorkgroupsPerDimension: parts.maxWorkgroupsPerDimension }),
    ]);
    return new BlockCache(device, parts, { age, mark, assign, fill, ageLayout, markLayout, assignLayout, fillLayout }, sort, capacity);
  }

  get capacity(): number {
    return this.slots.capacity;
  }

  /** 64 f32 per slot, voxel x + 4y + 16z of the slot's block. */
  get slotData(): GPUBuffer {
    return this.slots.slotData;
  }

  get slotAge(): GPUBuffer {
    return this.slots.slotAge;
  }

  get slotToBlock(): GPUBuffer {
    return this.slots.slotToBlock;
  }

  /** Bytes of the slot data and bookkeeping (including blockToSlot and the sort's scratch). */
  get byteSize(): number {
    const s = this.slots;
    const own = [s.slotData, s.slotAge, s.slotToBlock, s.availMask, s.availOffsets, s.availIds, s.availAges, s.newMask, s.newOffsets, s.newIds];
    return own.reduce((n, b) => n + b.size, 0) + this.blockToSlot.size + this.sort.capacity * 9;
  }

  private allocate(capacity: number): SlotBuffers {
    const d = this.device;
    const copy = GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST;
    const words = (label: string, extra = 0) => storageBuffer(d, `Isosurface.${label}`, capacity * 4, extra);
    return {
      capacity,
      slotData: storageBuffer(d, 'Isosurface.slotData', capacity * SLOT_BYTES, copy),
      slotAge: words('slotAge', copy),
      slotToBlock: words('slotToBlock', copy),
      availMask: words('availMask'),
      availOffsets: words('availOffsets'),
      availIds: words('availIds'),
      availAges: words('availAges'),
      newMask: words('newMask'),
      newOffsets: words('newOffsets'),
      newIds: words('newIds'),
    };
  }

  private makeGroups(): Groups {
    const d = this.device;
    const p = this.pipelines;
    const s = this.slots;
    const counters = this.parts.counters.buffer;
    return {
      age: bindGroup(d, 'Isosurface.ageSlots.bindGroup', p.ageLayout, [counters, s.slotToBlock, s.slotAge, s.availMask]),
      mark: bindGroup(d, 'Isosurface.markCached.bindGroup', p.markLayout, [counters, this.parts.activeIds, this.blockToSlot, s.slotAge, s.availMask, s.newMask]),
      assign: bindGroup(d, 'Isosurface.assignSlots.bindGroup', p.assignLayout, [counters, s.newIds, s.availIds, s.slotToBlock, this.blockToSlot, s.slotAge]),
    };
  }

  private destroySlots(s: SlotBuffers): void {
    for (const b of [s.slotData, s.slotAge, s.slotToBlock, s.availMask, s.availOffsets, s.availIds, s.availAges, s.newMask, s.newOffsets, s.newIds]) b.destroy();
  }

  /** Records words [begin, end) of `target` := NONE. At most FILL_SLOTS per submission. */
  private encodeFill(encoder: GPUCommandEncoder, target: GPUBuffer, begin: number, end: number): void {
    if (end <= begin) return;
    if (this.fillsRecorded >= FILL_SLOTS) throw new Error('BlockCache: too many fills in one submission');
    const offset = this.fillsRecorded++ * FILL_STRIDE;
    this.device.queue.writeBuffer(this.fillParams, offset, new Uint32Array([begin, end]));
    const pass = encoder.beginComputePass({ label: 'Isosurface.fillNone' });
    pass.setPipeline(this.pipelines.fill);
    pass.setBindGroup(0, this.device.createBindGroup({
      label: 'Isosurface.fillNone.bindGroup',
      layout: this.pipelines.fillLayout,
      entries: [
        { binding: 0, resource: { buffer: this.fillParams, size: 8 } },
        { binding: 1, resource: { buffer: target } },
      ],
    }), [offset]);
    dispatchLinear(pass, Math.ceil((end - begin) / 64), this.parts.maxWorkgroupsPerDimension);
    pass.end();
  }

  private submitFills(encoder: GPUCommandEncoder): void {
    this.device.queue.submit([encoder.finish()]);
    this.fillsRecorded = 0;
  }

  /** Empties every slot and block entry (submits). Capacity stays. */
  private clear(capacity: number): void {
    const encoder = this.device.createCommandEncoder({ label: 'Isosurface.clearCache' });
    this.encodeFill(encoder, this.blockToSlot, 0, this.parts.stream.info.blockCount);
    this.encodeFill(encoder, this.slots.slotToBlock, 0, capacity);
    this.encodeFill(encoder, this.slots.slotAge, 0, capacity);
    this.submitFills(encoder);
    this.parts.counters.set('slots', capacity);
    this.parts.counters.set('slotsUsed', 0);
  }

  /**
   * Empties the cache, reallocating it at `capacity` slots if that differs
   * (call between submissions; replaces slotData when the capacity changes).
   */
  reset(capacity = this.capacity): void {
    if (capacity !== this.capacity) {
      const old = this.slots;
      this.slots = this.allocate(capacity);
      this.groups = this.makeGroups();
      this.destroySlots(old);
      this.sort.grow(capacity);
      this.parts.scan.grow(capacity);
    }
    this.clear(capacity);
  }

  /**
   * Grows to `capacity` slots keeping every cached block where it is: the old
   * slot data, ages and maps are copied on the GPU, the new slots are empty
   * (age NONE: taken first). Call between submissions; replaces slotData.
   */
  grow(capacity: number): void {
    const old = this.slots;
    if (capacity <= old.capacity) return;
    const next = this.allocate(capacity);
    const encoder = this.device.createCommandEncoder({ label: 'Isosurface.growCache' });
    encoder.copyBufferToBuffer(old.slotData, 0, next.slotData, 0, old.capacity * SLOT_BYTES);
    encoder.copyBufferToBuffer(old.slotAge, 0, next.slotAge, 0, old.capacity * 4);
    encoder.copyBufferToBuffer(old.slotToBlock, 0, next.slotToBlock, 0, old.capacity * 4);
    this.encodeFill(encoder, next.slotAge, old.capacity, capacity);
    this.encodeFill(encoder, next.slotToBlock, old.capacity, capacity);
    this.submitFills(encoder);
    this.slots = next;
    this.groups = this.makeGroups();
    this.destroySlots(old);
    this.sort.grow(capacity);
    this.parts.scan.grow(capacity);
    this.parts.counters.set('slots', capacity);
  }

  /** Records the cache update (everything before the decode). */
  encodeUpdate(encoder: GPUCommandEncoder): void {
    const { counters, scan, compact, compactIds, activeIds } = this.parts;
    const s = this.slots;
    const args = counters.buffer;
    let pass = encoder.beginComputePass({ label: 'Isosurface.ageAndMark' });
    pass.setPipeline(this.pipelines.age);
    pass.setBindGroup(0, this.groups.age);
    pass.dispatchWorkgroupsIndirect(args, Counters.offset(A.slots));
    pass.setPipeline(this.pipelines.mark);
    pass.setBindGroup(0, this.groups.mark);
    pass.dispatchWorkgroupsIndirect(args, Counters.offset(A.mark));
    pass.end();
    scan.encode(encoder, { input: s.newMask, output: s.newOffsets, count: counters.count('activeGated'), totalOut: counters.count('new') });
    pass = encoder.beginComputePass({ label: 'Isosurface.planUpdate' });
    counters.encodePlanUpdate(pass);
    pass.end();
    const availScan = counters.count('availScan');
    scan.encode(encoder, { input: s.availMask, output: s.availOffsets, count: availScan, totalOut: counters.count('avail') });
    compact.encode(encoder, { mask: s.newMask, offsets: s.newOffsets, values: activeIds, output: s.newIds, count: counters.count('compactNew') });
    compactIds.encode(encoder, { mask: s.availMask, offsets: s.availOffsets, output: s.availIds, count: availScan });
    compact.encode(encoder, { mask: s.availMask, offsets: s.availOffsets, values: s.slotAge, output: s.availAges, count: availScan });
    // Oldest first; stable, so equal ages keep slot order (empty slots first
    // in slot order, since their key 0xffff is above every age).
    this.sort.encode(encoder, { keys: s.availAges, values: s.availIds, count: counters.count('avail'), descending: true, keyBits: AGE_KEY_BITS });
    pass = encoder.beginComputePass({ label: 'Isosurface.assignSlots' });
    pass.setPipeline(this.pipelines.assign);
    pass.setBindGroup(0, this.groups.assign);
    pass.dispatchWorkgroupsIndirect(args, Counters.offset(A.assign));
    pass.end();
  }

  /** Records the decode of the new blocks into their slots (count n_new on the GPU). */
  encodeDecode(encoder: GPUCommandEncoder): void {
    const { decoder, stream, counters } = this.parts;
    decoder.encodeDecodeBlocks(encoder, {
      stream: isChunked(stream) ? stream.blocks : stream,
      blockIds: this.slots.newIds,
      slotIds: this.slots.availIds,
      count: counters.count('new'),
      slots: this.slots.slotData,
    });
  }

  destroy(): void {
    this.destroySlots(this.slots);
    this.blockToSlot.destroy();
    this.fillParams.destroy();
    this.sort.destroy();
  }
}
