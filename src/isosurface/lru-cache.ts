// The GPU-driven LRU block cache (paper Algorithm 1, docs/design.md steps 2-3):
// slot <-> block maps, decoded slot data, the LRU order as a log with a count
// tree (lru.wgsl), and the per-computation update recorded from GPU counts
// only, in work proportional to the active and new blocks:
//
//   (log full?)      scan + compaction of the log's valid entries, rebuild_log
//                    (gated on the GPU: amortized over >= slots appends)
//   mark_cached      active cached blocks: their log entry becomes a hole; others are new
//   scan new         -> offsets, n_new
//   plan_update      "exit if n_new = 0": later counts become 0; log base and tail
//   compact          new block ids
//   pick_victims     new block i -> the (i + 1)-th valid log entry's slot (tree descent)
//   assign_slots     new block i -> that slot, evicting its block; its entry a hole
//   append_active    every active slot appended to the log, in active-list order
//   decode           the new blocks into their slots (ZfpDecoder.encodeDecodeBlocks)
//
// "Grow if n_new > n_avail" is decided on the GPU before any of this
// (plan_cache: the update fits iff active <= slots); when it does not fit,
// every count above is 0, the cache is left exactly as it was, and the host
// grows the cache when it reads the statistics (see isosurface.ts).
import type { StreamCompact, StreamCompactIds } from '../primitives/compact.ts';
import { ExclusiveScan } from '../primitives/scan.ts';
import type { ZfpDecoder } from '../zfp/decoder.ts';
import type { BlockSource } from '../zfp/gpu-stream.ts';
import { Counters } from './counters.ts';
import { bindGroup, bufferLayout, storageBuffer } from '../gpu/bindings.ts';
import { BindGroupCache } from '../gpu/bind-group-cache.ts';
import { dispatchWorkgroups } from '../gpu/dispatch.ts';
import { createComputePipeline } from '../gpu/pipeline-cache.ts';
import { A, logBytesFor, logSizeFor, logTreeWords, SLOT_BYTES } from './layout.ts';
import { NoneFill } from './none-fill.ts';
import { isosurfaceWgsl } from './wgsl.ts';

export interface BlockCacheParts {
  stream: BlockSource;
  decoder: ZfpDecoder;
  counters: Counters;
  /** Sized to the slots (grown with the cache; shared with the block MC, whose counts are per active block <= slots). */
  scan: ExclusiveScan;
  compact: StreamCompact;
  compactIds: StreamCompactIds;
  /** The active list (ActiveBlocks.activeIds). */
  activeIds: GPUBuffer;
  maxWorkgroupsPerDimension: number;
  /** Block ids (a stream's blocks, a pool's slots x blocks per chunk): blockToSlot holds one entry per id. */
  blockIds: number;
}

/** Bytes per slot of the buffers sized by the capacity (slot data, maps, slot positions, victims, new mask/offsets/ids); the log adds logBytesFor(slots). */
export const CACHE_BYTES_PER_SLOT = SLOT_BYTES + 4 * 6;

interface SlotBuffers {
  capacity: number;
  logSize: number;
  slotData: GPUBuffer;
  slotToBlock: GPUBuffer;
  slotPos: GPUBuffer;
  victims: GPUBuffer;
  newMask: GPUBuffer;
  newOffsets: GPUBuffer;
  newIds: GPUBuffer;
  log: GPUBuffer;
  valid: GPUBuffer;
  logOffsets: GPUBuffer;
  logScratch: GPUBuffer;
  tree: GPUBuffer;
}

interface Groups {
  mark: GPUBindGroup;
  pick: GPUBindGroup;
  assign: GPUBindGroup;
  append: GPUBindGroup;
  /** rebuild_log after an in-computation compaction (fresh 0, kept from the counters). */
  compacted: GPUBindGroup;
}

interface Pipelines {
  mark: GPUComputePipeline;
  pick: GPUComputePipeline;
  assign: GPUComputePipeline;
  append: GPUComputePipeline;
  rebuild: GPUComputePipeline;
  rebuildCompacted: GPUComputePipeline;
  markLayout: GPUBindGroupLayout;
  pickLayout: GPUBindGroupLayout;
  assignLayout: GPUBindGroupLayout;
  appendLayout: GPUBindGroupLayout;
  rebuildLayout: GPUBindGroupLayout;
  rebuildCompactedLayout: GPUBindGroupLayout;
  forget: GPUComputePipeline;
  forgetLayout: GPUBindGroupLayout;
}

/** Bytes between the two records of the rebuild parameters (the uniform offset alignment). */
const PARAMS_STRIDE = 256;

export class BlockCache {
  /** Per block: its slot, or NONE. */
  readonly blockToSlot: GPUBuffer;
  private slots!: SlotBuffers;
  private groups!: Groups;
  /** rebuild_log parameters: [0] for a compaction (constant), [1] written by reset and growth. */
  private readonly rebuildParams: GPUBuffer;
  private readonly forgetGroups = new BindGroupCache();

  private constructor(
    private readonly device: GPUDevice,
    private readonly parts: BlockCacheParts,
    private readonly pipelines: Pipelines,
    /** Sized to the log positions. */
    private readonly logScan: ExclusiveScan,
    /** Empties the maps (none-fill.ts). */
    private readonly fill: NoneFill,
    capacity: number,
  ) {
    const blocks = parts.blockIds;
    this.blockToSlot = storageBuffer(device, 'Isosurface.blockToSlot', blocks * 4, GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST);
    this.rebuildParams = device.createBuffer({
      label: 'Isosurface.rebuildParams',
      size: 2 * PARAMS_STRIDE,
      usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
    });
    device.queue.writeBuffer(this.rebuildParams, 0, new Uint32Array([0, 0, 1, 0]));
    this.slots = this.allocate(capacity);
    this.groups = this.makeGroups();
    this.clear(this.slots.capacity);
  }

  static async create(device: GPUDevice, parts: BlockCacheParts, capacity: number): Promise<BlockCache> {
    const markLayout = bufferLayout(device, 'Isosurface.markCached.layout', ['read', 'read', 'read', 'read', 'rw', 'rw', 'rw']);
    const pickLayout = bufferLayout(device, 'Isosurface.pickVictims.layout', ['read', 'read', 'read', 'rw', 'read']);
    const assignLayout = bufferLayout(device, 'Isosurface.assignSlots.layout', ['read', 'read', 'read', 'rw', 'rw', 'read', 'rw', 'rw']);
    const appendLayout = bufferLayout(device, 'Isosurface.appendActive.layout', ['read', 'read', 'read', 'rw', 'rw', 'rw', 'rw']);
    const rebuildLayout = bufferLayout(device, 'Isosurface.rebuildLog.layout', ['uniform', 'rw', 'read', 'rw', 'rw', 'rw', 'rw']);
    const rebuildCompactedLayout = bufferLayout(device, 'Isosurface.rebuildLogCompacted.layout', [
      'uniform',
      'read',
      'read',
      'rw',
      'rw',
      'rw',
      'rw',
    ]);
    const forgetLayout = bufferLayout(device, 'Isosurface.forgetSlots.layout', ['read', 'uniform', 'rw', 'rw']);
    const constants = { MAX_WG_PER_DIM: parts.maxWorkgroupsPerDimension };
    const wgsl = isosurfaceWgsl.lru;
    const [mark, pick, assign, append, rebuild, rebuildCompacted, forget, logScan, fill] = await Promise.all([
      createComputePipeline(device, 'Isosurface.markCached', wgsl, 'mark_cached', { layout: [markLayout], constants }),
      createComputePipeline(device, 'Isosurface.pickVictims', wgsl, 'pick_victims_of_new', { layout: [pickLayout], constants }),
      createComputePipeline(device, 'Isosurface.assignSlots', wgsl, 'assign_slots', { layout: [assignLayout], constants }),
      createComputePipeline(device, 'Isosurface.appendActive', wgsl, 'append_active', { layout: [appendLayout], constants }),
      createComputePipeline(device, 'Isosurface.rebuildLog', wgsl, 'rebuild_log', { layout: [rebuildLayout], constants }),
      createComputePipeline(device, 'Isosurface.rebuildLogCompacted', wgsl, 'rebuild_log_compacted', {
        layout: [rebuildCompactedLayout],
        constants,
      }),
      createComputePipeline(device, 'Isosurface.forgetSlots', wgsl, 'forget_slots', { layout: [forgetLayout], constants }),
      ExclusiveScan.create(device, { capacity: logSizeFor(capacity), maxWorkgroupsPerDimension: parts.maxWorkgroupsPerDimension }),
      NoneFill.create(device, parts.maxWorkgroupsPerDimension),
    ]);
    const pipelines = {
      mark,
      pick,
      assign,
      append,
      rebuild,
      rebuildCompacted,
      markLayout,
      pickLayout,
      assignLayout,
      appendLayout,
      rebuildLayout,
      rebuildCompactedLayout,
      forget,
      forgetLayout,
    };
    return new BlockCache(device, parts, pipelines, logScan, fill, capacity);
  }

  get capacity(): number {
    return this.slots.capacity;
  }

  /**
   * A chunk pool's slots in `list` ((slot, chunk) pairs, `params`: count and
   * ids per slot) got other chunks: what was decoded from them is forgotten
   * (lru.wgsl forget_slots). Recorded into the caller's pass.
   */
  encodeForget(pass: GPUComputePassEncoder, list: GPUBuffer, params: GPUBuffer, count: number, perChunk: number): void {
    const group = this.forgetGroups
      .ref(list)
      .ref(this.slots.slotToBlock)
      .get(() =>
        bindGroup(this.device, 'Isosurface.forgetSlots.bindGroup', this.pipelines.forgetLayout, [
          list,
          params,
          this.blockToSlot,
          this.slots.slotToBlock,
        ]),
      );
    pass.setPipeline(this.pipelines.forget);
    pass.setBindGroup(0, group);
    dispatchWorkgroups(pass, Math.ceil((count * perChunk) / 64), this.parts.maxWorkgroupsPerDimension);
  }

  /** 64 f32 per slot, voxel x + 4y + 16z of the slot's block. */
  get slotData(): GPUBuffer {
    return this.slots.slotData;
  }

  get slotToBlock(): GPUBuffer {
    return this.slots.slotToBlock;
  }

  /** The LRU log (slots, least recently used first) and its valid flags; logSize positions. */
  get lruLog(): { log: GPUBuffer; valid: GPUBuffer; size: number } {
    return { log: this.slots.log, valid: this.slots.valid, size: this.slots.logSize };
  }

  /** Bytes of the slot data and bookkeeping (including blockToSlot and the LRU log). */
  get byteSize(): number {
    return this.ownBuffers(this.slots).reduce((n, b) => n + b.size, 0) + this.blockToSlot.size;
  }

  private ownBuffers(s: SlotBuffers): GPUBuffer[] {
    return [
      s.slotData,
      s.slotToBlock,
      s.slotPos,
      s.victims,
      s.newMask,
      s.newOffsets,
      s.newIds,
      s.log,
      s.valid,
      s.logOffsets,
      s.logScratch,
      s.tree,
    ];
  }

  private allocate(capacity: number): SlotBuffers {
    const d = this.device;
    const copy = GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST;
    const words = (label: string, count: number, extra = 0) => storageBuffer(d, `Isosurface.${label}`, count * 4, extra);
    const logSize = logSizeFor(capacity);
    const s: SlotBuffers = {
      capacity,
      logSize,
      slotData: storageBuffer(d, 'Isosurface.slotData', capacity * SLOT_BYTES, copy),
      slotToBlock: words('slotToBlock', capacity, copy),
      slotPos: words('slotPos', capacity),
      victims: words('victims', capacity),
      newMask: words('newMask', capacity),
      newOffsets: words('newOffsets', capacity),
      newIds: words('newIds', capacity),
      log: words('lruLog', logSize, GPUBufferUsage.COPY_SRC),
      valid: words('lruValid', logSize, GPUBufferUsage.COPY_SRC),
      logOffsets: words('lruLogOffsets', logSize),
      logScratch: words('lruLogScratch', logSize),
      tree: words('lruTree', logTreeWords(logSize)),
    };
    if (this.ownBuffers(s).reduce((n, b) => n + b.size, 0) !== capacity * CACHE_BYTES_PER_SLOT + logBytesFor(capacity))
      throw new Error('BlockCache: byte accounting out of date');
    return s;
  }

  private makeGroups(): Groups {
    const d = this.device;
    const p = this.pipelines;
    const s = this.slots;
    const counters = this.parts.counters.buffer;
    const { activeIds } = this.parts;
    return {
      mark: bindGroup(d, 'Isosurface.markCached.bindGroup', p.markLayout, [
        counters,
        activeIds,
        this.blockToSlot,
        s.slotPos,
        s.valid,
        s.tree,
        s.newMask,
      ]),
      pick: bindGroup(d, 'Isosurface.pickVictims.bindGroup', p.pickLayout, [counters, s.tree, s.log, s.victims, s.valid]),
      assign: bindGroup(d, 'Isosurface.assignSlots.bindGroup', p.assignLayout, [
        counters,
        s.newIds,
        s.victims,
        s.slotToBlock,
        this.blockToSlot,
        s.slotPos,
        s.valid,
        s.tree,
      ]),
      append: bindGroup(d, 'Isosurface.appendActive.bindGroup', p.appendLayout, [
        counters,
        activeIds,
        this.blockToSlot,
        s.log,
        s.slotPos,
        s.valid,
        s.tree,
      ]),
      compacted: this.rebuildGroup(s, s.logScratch, 0, this.pipelines.rebuildCompactedLayout),
    };
  }

  private rebuildGroup(s: SlotBuffers, scratch: GPUBuffer, params: 0 | 1, layout = this.pipelines.rebuildLayout): GPUBindGroup {
    return bindGroup(this.device, 'Isosurface.rebuildLog.bindGroup', layout, [
      { buffer: this.rebuildParams, offset: params * PARAMS_STRIDE, size: 16 },
      this.parts.counters.buffer,
      scratch,
      s.log,
      s.slotPos,
      s.valid,
      s.tree,
    ]);
  }

  private destroySlots(s: SlotBuffers): void {
    for (const b of this.ownBuffers(s)) b.destroy();
  }

  private submitFills(encoder: GPUCommandEncoder): void {
    this.device.queue.submit([encoder.finish()]);
    this.fill.submitted();
  }

  /** Records rebuild_log over the log of `s` with host parameters (fresh slots first_fresh.., then the kept entries of `scratch` if useKept). */
  private encodeRebuild(
    encoder: GPUCommandEncoder,
    s: SlotBuffers,
    scratch: GPUBuffer,
    fresh: number,
    firstFresh: number,
    useKept: boolean,
  ): void {
    this.device.queue.writeBuffer(this.rebuildParams, PARAMS_STRIDE, new Uint32Array([fresh, firstFresh, useKept ? 1 : 0, 0]));
    this.parts.counters.set('logSize', s.logSize);
    const pass = encoder.beginComputePass({ label: 'Isosurface.rebuildLog' });
    pass.setPipeline(this.pipelines.rebuild);
    pass.setBindGroup(0, this.rebuildGroup(s, scratch, 1));
    dispatchWorkgroups(pass, Math.ceil((2 * s.logSize) / 64), this.parts.maxWorkgroupsPerDimension);
    pass.end();
  }

  /** Empties every slot and block entry (submits): the log holds the slots in order, all empty. Capacity stays. */
  private clear(capacity: number): void {
    const encoder = this.device.createCommandEncoder({ label: 'Isosurface.clearCache' });
    this.fill.encode(encoder, this.blockToSlot, 0, this.parts.blockIds);
    this.fill.encode(encoder, this.slots.slotToBlock, 0, capacity);
    this.encodeRebuild(encoder, this.slots, this.slots.logScratch, capacity, 0, false);
    this.submitFills(encoder);
    this.parts.counters.set('slots', capacity);
    this.parts.counters.set('slotsUsed', 0);
  }

  /**
   * Empties the cache, reallocating it at `capacity` slots if that differs
   * (call between submissions; replaces slotData when the capacity changes).
   * The capacity may shrink back this way (Isosurface.resetCache).
   */
  reset(capacity = this.capacity): void {
    if (capacity !== this.capacity) {
      // nothing is kept: the old slots go before the new are made (never both held)
      this.destroySlots(this.slots);
      this.slots = this.allocate(capacity);
      this.groups = this.makeGroups();
      this.logScan.grow(this.slots.logSize);
      this.parts.scan.grow(capacity);
    }
    this.clear(capacity);
  }

  /**
   * Grows to `capacity` slots keeping every cached block where it is: the old
   * slot data and maps are copied on the GPU, the new slots are empty and
   * come first in the LRU log, followed by the old log's valid entries in
   * order (scanned and compacted on the GPU). Call between submissions;
   * replaces slotData.
   */
  grow(capacity: number): void {
    const old = this.slots;
    if (capacity <= old.capacity) return;
    const next = this.allocate(capacity);
    const { counters, compact } = this.parts;
    this.logScan.grow(Math.max(old.logSize, next.logSize));
    const encoder = this.device.createCommandEncoder({ label: 'Isosurface.growCache' });
    encoder.copyBufferToBuffer(old.slotData, 0, next.slotData, 0, old.capacity * SLOT_BYTES);
    encoder.copyBufferToBuffer(old.slotToBlock, 0, next.slotToBlock, 0, old.capacity * 4);
    this.fill.encode(encoder, next.slotToBlock, old.capacity, capacity);
    // The old log's valid entries, in order, into the new scratch (count: the old tail).
    this.logScan.encode(encoder, {
      input: old.valid,
      output: next.logOffsets,
      count: counters.count('logTail'),
      totalOut: counters.count('logValid'),
    });
    compact.encode(encoder, {
      mask: old.valid,
      offsets: next.logOffsets,
      values: old.log,
      output: next.logScratch,
      count: counters.count('logTail'),
    });
    this.encodeRebuild(encoder, next, next.logScratch, capacity - old.capacity, old.capacity, true);
    this.submitFills(encoder);
    this.slots = next;
    this.groups = this.makeGroups();
    this.destroySlots(old);
    this.parts.scan.grow(capacity);
    counters.set('slots', capacity);
  }

  /** Records the cache update (everything before the decode). */
  encodeUpdate(encoder: GPUCommandEncoder): void {
    const { counters, scan, compact, activeIds } = this.parts;
    const s = this.slots;
    const args = counters.buffer;
    const g = this.groups;
    // A full log is compacted first (all counts 0 otherwise).
    this.logScan.encode(encoder, {
      input: s.valid,
      output: s.logOffsets,
      count: counters.count('logCompact'),
      totalOut: counters.count('logValid'),
    });
    compact.encode(encoder, {
      mask: s.valid,
      offsets: s.logOffsets,
      values: s.log,
      output: s.logScratch,
      count: counters.count('logCompact'),
    });
    let pass = encoder.beginComputePass({ label: 'Isosurface.markCached' });
    pass.setPipeline(this.pipelines.rebuildCompacted);
    pass.setBindGroup(0, g.compacted);
    pass.dispatchWorkgroupsIndirect(args, Counters.offset(A.slots));
    pass.setPipeline(this.pipelines.mark);
    pass.setBindGroup(0, g.mark);
    pass.dispatchWorkgroupsIndirect(args, Counters.offset(A.mark));
    pass.end();
    scan.encode(encoder, { input: s.newMask, output: s.newOffsets, count: counters.count('activeGated'), totalOut: counters.count('new') });
    pass = encoder.beginComputePass({ label: 'Isosurface.planUpdate' });
    counters.encodePlanUpdate(pass);
    pass.end();
    compact.encode(encoder, {
      mask: s.newMask,
      offsets: s.newOffsets,
      values: activeIds,
      output: s.newIds,
      count: counters.count('compactNew'),
    });
    pass = encoder.beginComputePass({ label: 'Isosurface.assignSlots' });
    pass.setPipeline(this.pipelines.pick);
    pass.setBindGroup(0, g.pick);
    pass.dispatchWorkgroupsIndirect(args, Counters.offset(A.assign));
    pass.setPipeline(this.pipelines.assign);
    pass.setBindGroup(0, g.assign);
    pass.dispatchWorkgroupsIndirect(args, Counters.offset(A.assign));
    pass.setPipeline(this.pipelines.append);
    pass.setBindGroup(0, g.append);
    pass.dispatchWorkgroupsIndirect(args, Counters.offset(A.mark));
    pass.end();
  }

  /** Records the decode of the new blocks into their slots (count n_new on the GPU). */
  encodeDecode(encoder: GPUCommandEncoder): void {
    const { decoder, stream, counters } = this.parts;
    decoder.encodeDecodeBlocks(encoder, {
      stream,
      blockIds: this.slots.newIds,
      slotIds: this.slots.victims,
      count: counters.count('new'),
      slots: this.slots.slotData,
    });
  }

  destroy(): void {
    this.destroySlots(this.slots);
    this.blockToSlot.destroy();
    this.fill.destroy();
    this.rebuildParams.destroy();
    this.logScan.destroy();
  }
}
