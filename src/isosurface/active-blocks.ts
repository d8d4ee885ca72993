// Active blocks (docs/design.md step 1), hierarchically: per-block value ranges
// from the decoder at load, widened once to each block's 27-block
// neighbourhood, and per group of edge^3 blocks the range of its blocks'
// neighbourhood ranges (shaders/isosurface/active_groups.wgsl). Per isovalue:
//   mark_active_groups  one compare per group; scan (-> activeGroups) and ID compaction
//   plan_groups         active groups x blocks per group, dispatch arguments
//   mark_group_blocks   one compare per block of the active groups (with its id)
//   scan (-> active) and compaction of the ids: the active list I_active
// So only the groups scale with the volume; a surface costs the same in a
// small volume and in a large mostly-empty one. The active list is
// group-major (lru-model.ts activeBlocks gives the same order).
// A chunk pool's groups are its slots and its blocks have pool ids
// (block-ids.ts): everything here is sized by the pool, and the ranges
// follow the chunks as they come and go (encodeChunkUpdates).
import { dispatchWorkgroups } from '../gpu/dispatch.ts';
import { readF32 } from '../gpu/buffers.ts';
import type { ExclusiveScan } from '../primitives/scan.ts';
import type { StreamCompact, StreamCompactIds } from '../primitives/compact.ts';
import type { ChunkedVolume, SlotChange } from '../zfp/chunked-volume.ts';
import type { ZfpDecoder } from '../zfp/decoder.ts';
import type { BlockSource, ZfpGpuStream } from '../zfp/gpu-stream.ts';
import { Counters } from './counters.ts';
import { bindGroup, bufferLayout, storageBuffer } from '../gpu/bindings.ts';
import { createComputePipeline } from '../gpu/pipeline-cache.ts';
import { SlotRangeReducer } from './slot-ranges.ts';
import type { BlockIds } from './block-ids.ts';
import { A } from './layout.ts';
import { isosurfaceWgsl } from './wgsl.ts';

export interface ActiveBlocksParts {
  /** A whole stream (ranges computed at load), or a chunk pool (ranges follow the chunks as they come and go). */
  stream: BlockSource;
  decoder: ZfpDecoder;
  /** VolumeParams uniform (common.wgsl). */
  volume: GPUBuffer;
  counters: Counters;
  scan: ExclusiveScan;
  compact: StreamCompact;
  compactIds: StreamCompactIds;
  maxWorkgroupsPerDimension: number;
  /** Blocks per group along each axis. */
  groupEdge: number;
  /** How blocks are named (a stream's raster ids, a pool's ids). */
  ids: BlockIds;
}

/** The group grid of a block grid: ceil(grid / edge) per axis. */
export function groupGrid(blockGrid: readonly number[], edge: number): [number, number, number] {
  return [Math.ceil(blockGrid[0] / edge), Math.ceil(blockGrid[1] / edge), Math.ceil(blockGrid[2] / edge)];
}

export class ActiveBlocks {
  /** 2 f32 (min, max) per block over its voxels inside the volume. */
  readonly blockRanges: GPUBuffer;
  /** 2 f32 per block: min and max over the block and its 26 neighbours. */
  readonly neighbourhoodRanges: GPUBuffer;
  /** 2 f32 per group: min and max over its blocks' neighbourhood ranges. */
  readonly groupRanges: GPUBuffer;
  readonly groupMask: GPUBuffer;
  readonly groupOffsets: GPUBuffer;
  readonly activeGroupIds: GPUBuffer;
  /** Per block of the active groups (groups x edge^3 entries at most): mask, offsets, block id. */
  readonly blockMask: GPUBuffer;
  readonly blockOffsets: GPUBuffer;
  readonly blockIds: GPUBuffer;
  /** Active block ids, group-major; the first counters[active] entries are valid. */
  readonly activeIds: GPUBuffer;
  readonly groupCount: number;
  readonly groupSize: number;
  private readonly groupParams: GPUBuffer;
  private readonly common: GPUBindGroup;
  private readonly markGroupsGroup: GPUBindGroup;
  private readonly markBlocksGroup: GPUBindGroup;
  /** Chunked volumes only: the changed chunks and the bind groups of their range updates. */
  private readonly chunkUpdate?: ChunkUpdate;
  /** Chunked volumes only: [min, max] per slot, reduced on the GPU (readSlotRanges). */
  private slotRanges?: SlotRangeReducer;

  private constructor(
    private readonly device: GPUDevice,
    private readonly parts: ActiveBlocksParts,
    private readonly markGroups: GPUComputePipeline,
    private readonly markBlocks: GPUComputePipeline,
    layouts: ActiveLayouts,
    chunkPipelines?: { neighbourhood: GPUComputePipeline; groups: GPUComputePipeline },
  ) {
    const { ids } = parts;
    const blockCount = ids.count;
    const edge = parts.groupEdge;
    const pool = ids.pool;
    // a stream's groups tile its block grid; a pool's are its slots
    const grid: [number, number, number] = pool ? [pool.poolChunks, 1, 1] : groupGrid(parts.stream.info.blockGrid, edge);
    this.groupCount = grid[0] * grid[1] * grid[2];
    this.groupSize = edge ** 3;
    const entries = this.groupCount * this.groupSize;
    // A pool starts empty: every block has the empty range until its chunk arrives (group ranges start at [0, 0], never active).
    this.blockRanges = pool ? emptyRanges(device, blockCount) : parts.decoder.computeBlockRanges(parts.stream as ZfpGpuStream);
    this.neighbourhoodRanges = storageBuffer(device, 'Isosurface.neighbourhoodRanges', blockCount * 8);
    this.groupRanges = storageBuffer(device, 'Isosurface.groupRanges', this.groupCount * 8);
    this.groupMask = storageBuffer(device, 'Isosurface.groupMask', this.groupCount * 4);
    this.groupOffsets = storageBuffer(device, 'Isosurface.groupOffsets', this.groupCount * 4);
    this.activeGroupIds = storageBuffer(device, 'Isosurface.activeGroupIds', this.groupCount * 4);
    this.blockMask = storageBuffer(device, 'Isosurface.groupBlockMask', entries * 4);
    this.blockOffsets = storageBuffer(device, 'Isosurface.groupBlockOffsets', entries * 4);
    this.blockIds = storageBuffer(device, 'Isosurface.groupBlockIds', entries * 4);
    this.activeIds = storageBuffer(device, 'Isosurface.activeIds', blockCount * 4, GPUBufferUsage.COPY_SRC); // read back for the view cut's per-chunk triangles
    this.groupParams = device.createBuffer({
      label: 'Isosurface.groupParams',
      size: 32,
      usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
    });
    device.queue.writeBuffer(this.groupParams, 0, new Uint32Array([...grid, edge, this.groupCount, this.groupSize, 0, 0]));
    parts.counters.set('groups', this.groupCount);
    parts.counters.set('groupSize', this.groupSize);
    this.common = bindGroup(device, 'Isosurface.activeGroups.bindGroup', layouts.common, [parts.volume, this.groupParams]);
    this.markGroupsGroup = bindGroup(
      device,
      'Isosurface.markActiveGroups.bindGroup',
      layouts.markGroups,
      [this.groupRanges, this.groupMask],
      2,
    );
    this.markBlocksGroup = bindGroup(
      device,
      'Isosurface.markGroupBlocks.bindGroup',
      layouts.markBlocks,
      [parts.counters.buffer, this.activeGroupIds, this.neighbourhoodRanges, this.blockMask, this.blockIds],
      4,
    );
    if (pool && chunkPipelines) {
      if (pool.chunkBlocks !== edge)
        throw new RangeError(
          `${pool.info.fileName}: the groups must be the chunks (groupEdgeBlocks ${edge}, chunk edge ${pool.chunkBlocks} blocks)`,
        );
      const uniform = (label: string, size: number) =>
        device.createBuffer({ label, size, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
      const decodeParams = uniform('Isosurface.changedChunks.decodeParams', 16);
      const regionParams = uniform('Isosurface.changedChunks.regionParams', 32);
      const groupParams = uniform('Isosurface.changedChunks.groupParams', 32);
      this.chunkUpdate = {
        pool,
        changes: pool.changeLog(),
        list: null,
        listEntries: 0,
        decodeParams,
        regionParams,
        groupParams,
        neighbourhood: chunkPipelines.neighbourhood,
        groups: chunkPipelines.groups,
        neighbourhoodGroup: bindGroup(device, 'Isosurface.neighbourhoodRange.bindGroup', layouts.neighbourhood, [
          parts.volume,
          this.blockRanges,
          this.neighbourhoodRanges,
        ]),
        regionGroup: null,
        loadGroup: bindGroup(device, 'Isosurface.groupRange.bindGroup', layouts.load, [this.neighbourhoodRanges, this.groupRanges]),
        changedGroup: null,
        layouts,
        words: new Uint32Array(8),
      };
    }
  }

  /** The change list, at least `entries` (slot, chunk) pairs long (made again, with its bind groups, when it must grow). */
  private changeList(u: ChunkUpdate, entries: number): GPUBuffer {
    if (!u.list || u.listEntries < entries) {
      u.list?.destroy();
      u.listEntries = Math.max(entries, 2 * u.pool.poolChunks + 16);
      u.list = this.device.createBuffer({
        label: 'Isosurface.changedChunks',
        size: u.listEntries * 8,
        usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST,
      });
      u.regionGroup = bindGroup(this.device, 'Isosurface.neighbourhoodRangeChunks.bindGroup', u.layouts.region, [u.list, u.regionParams]);
      u.changedGroup = bindGroup(this.device, 'Isosurface.groupRangeChunks.bindGroup', u.layouts.changed, [u.list, u.groupParams]);
    }
    return u.list;
  }

  /**
   * Chunked volumes: records the range updates of the slots whose chunk
   * arrived or left since the last surface (their blocks' ranges from the
   * pool, `forget` dropping what the cache decoded from those slots, the
   * neighbourhood ranges within one block of those chunks, the ranges of
   * their slots and of the resident chunks around them). Cost follows the
   * changes. Call right before the submission that follows (the list is
   * written with queue.writeBuffer).
   */
  encodeChunkUpdates(
    encoder: GPUCommandEncoder,
    forget: (pass: GPUComputePassEncoder, list: GPUBuffer, params: GPUBuffer, count: number) => void,
  ): number {
    const u = this.chunkUpdate;
    if (!u) return 0;
    const changed: SlotChange[] = u.changes.take();
    if (changed.length === 0) return 0;
    const { device } = this;
    const count = changed.length;
    const cb = u.pool.chunkBlocks;
    const list = this.changeList(u, count);
    const pairs = new Uint32Array(2 * count);
    changed.forEach((c, i) => pairs.set([c.slot, c.chunk], 2 * i));
    device.queue.writeBuffer(list, 0, pairs);
    u.words.set([count, cb ** 3, 0, 0]);
    device.queue.writeBuffer(u.decodeParams, 0, u.words, 0, 4);
    u.words.set([count, cb, 0, 0, ...u.pool.layout.chunkGrid, 0]);
    device.queue.writeBuffer(u.regionParams, 0, u.words, 0, 8);
    u.words.set([count, 0, 0, 0, ...u.pool.layout.chunkGrid, 0]);
    device.queue.writeBuffer(u.groupParams, 0, u.words, 0, 8);
    const { ids } = this.parts;
    const pass = encoder.beginComputePass({ label: 'Isosurface.chunkUpdates' });
    this.parts.decoder.encodeChunkBlockRanges(pass, {
      pool: u.pool,
      chunkList: list,
      params: u.decodeParams,
      count,
      ranges: this.blockRanges,
    });
    forget(pass, list, u.decodeParams, count);
    pass.setPipeline(u.neighbourhood);
    pass.setBindGroup(0, u.neighbourhoodGroup);
    pass.setBindGroup(1, u.regionGroup!);
    ids.bind(pass, 2);
    dispatchWorkgroups(pass, Math.ceil((count * (cb + 2) ** 3) / 64), this.parts.maxWorkgroupsPerDimension);
    pass.setPipeline(u.groups);
    pass.setBindGroup(0, this.common);
    pass.setBindGroup(1, u.loadGroup);
    pass.setBindGroup(2, u.changedGroup!);
    ids.bind(pass, 3);
    dispatchWorkgroups(pass, Math.ceil((count * 27) / 64), this.parts.maxWorkgroupsPerDimension);
    pass.end();
    return count;
  }

  /** Computes the block ranges, their neighbourhood ranges and the group ranges (one submission). */
  static async create(device: GPUDevice, parts: ActiveBlocksParts): Promise<ActiveBlocks> {
    const layouts: ActiveLayouts = {
      neighbourhood: bufferLayout(device, 'Isosurface.neighbourhoodRange.layout', ['uniform', 'read', 'rw']),
      region: bufferLayout(device, 'Isosurface.neighbourhoodRangeChunks.layout', ['read', 'uniform']),
      common: bufferLayout(device, 'Isosurface.activeGroups.layout', ['uniform', 'uniform']),
      load: bufferLayout(device, 'Isosurface.groupRange.layout', ['read', 'rw']),
      markGroups: bufferLayout(device, 'Isosurface.markActiveGroups.layout', ['read', 'rw'], 2),
      markBlocks: bufferLayout(device, 'Isosurface.markGroupBlocks.layout', ['read', 'read', 'read', 'rw', 'rw'], 4),
      changed: bufferLayout(device, 'Isosurface.groupRangeChunks.layout', ['read', 'uniform']),
    };
    const neighbourhoodLayout = layouts.neighbourhood;
    const constants = { MAX_WG_PER_DIM: parts.maxWorkgroupsPerDimension };
    const { ids } = parts;
    const groups = [...isosurfaceWgsl.activeGroups, ids.part];
    const blocks = [...isosurfaceWgsl.activeBlocks, ids.part];
    const pooled = ids.kind === 'pool';
    const [neighbourhood, groupRange, markGroups, markBlocks, chunkNeighbourhood, chunkGroups] = await Promise.all([
      pooled
        ? undefined
        : createComputePipeline(device, 'Isosurface.neighbourhoodRange', blocks, 'neighbourhood_range', {
            layout: [neighbourhoodLayout],
            constants,
          }),
      pooled
        ? undefined
        : createComputePipeline(device, 'Isosurface.groupRange', groups, 'group_range', {
            layout: [layouts.common, layouts.load],
            constants,
          }),
      createComputePipeline(device, 'Isosurface.markActiveGroups', groups, 'mark_active_groups', {
        // a pool's tables: the groups of idle chunks are never active
        layout: ids.layouts([layouts.common, layouts.markGroups]),
        constants,
      }),
      createComputePipeline(device, 'Isosurface.markGroupBlocks', groups, 'mark_group_blocks', {
        layout: ids.layouts([layouts.common, layouts.markBlocks]),
        constants,
      }),
      pooled
        ? createComputePipeline(device, 'Isosurface.neighbourhoodRangeChunks', blocks, 'neighbourhood_range_chunks', {
            layout: ids.layouts([neighbourhoodLayout, layouts.region]),
            constants,
          })
        : undefined,
      pooled
        ? createComputePipeline(device, 'Isosurface.groupRangeChunks', groups, 'group_range_chunks', {
            layout: ids.layouts([layouts.common, layouts.load, layouts.changed]),
            constants,
          })
        : undefined,
    ]);
    const chunkPipelines = chunkNeighbourhood && chunkGroups ? { neighbourhood: chunkNeighbourhood, groups: chunkGroups } : undefined;
    const active = new ActiveBlocks(device, parts, markGroups, markBlocks, layouts, chunkPipelines);
    if (ids.pool) active.slotRanges = await SlotRangeReducer.create(device, active.blockRanges, ids.pool.chunkBlocks ** 3);
    if (neighbourhood && groupRange) {
      // a whole stream: every range at once
      const encoder = device.createCommandEncoder({ label: 'Isosurface.neighbourhoodRanges' });
      const pass = encoder.beginComputePass({ label: 'Isosurface.neighbourhoodRanges' });
      pass.setPipeline(neighbourhood);
      pass.setBindGroup(
        0,
        bindGroup(device, 'Isosurface.neighbourhoodRange.bindGroup', neighbourhoodLayout, [
          parts.volume,
          active.blockRanges,
          active.neighbourhoodRanges,
        ]),
      );
      dispatchWorkgroups(pass, Math.ceil(ids.count / 64), parts.maxWorkgroupsPerDimension);
      pass.setPipeline(groupRange);
      pass.setBindGroup(0, active.common);
      pass.setBindGroup(
        1,
        bindGroup(device, 'Isosurface.groupRange.bindGroup', layouts.load, [active.neighbourhoodRanges, active.groupRanges]),
      );
      dispatchWorkgroups(pass, Math.ceil(active.groupCount / 64), parts.maxWorkgroupsPerDimension);
      pass.end();
      device.queue.submit([encoder.finish()]);
    }
    return active;
  }

  /** Block ids (a stream's blocks, a pool's slots x blocks per chunk). */
  get blockCount(): number {
    return this.parts.ids.count;
  }

  /** Entries the scan must hold: every block of every group. */
  get scanCapacity(): number {
    return this.groupCount * this.groupSize;
  }

  /** Records the selection: active groups, then the active list and its length (counters.active). */
  encode(encoder: GPUCommandEncoder): void {
    const { counters, scan, compact, compactIds, maxWorkgroupsPerDimension } = this.parts;
    let pass = encoder.beginComputePass({ label: 'Isosurface.markActiveGroups' });
    pass.setPipeline(this.markGroups);
    pass.setBindGroup(0, this.common);
    pass.setBindGroup(1, this.markGroupsGroup);
    this.parts.ids.bind(pass, 2);
    dispatchWorkgroups(pass, Math.ceil(this.groupCount / 64), maxWorkgroupsPerDimension);
    pass.end();
    const groups = counters.count('groups');
    scan.encode(encoder, { input: this.groupMask, output: this.groupOffsets, count: groups, totalOut: counters.count('activeGroups') });
    compactIds.encode(encoder, { mask: this.groupMask, offsets: this.groupOffsets, output: this.activeGroupIds, count: groups });
    pass = encoder.beginComputePass({ label: 'Isosurface.markGroupBlocks' });
    counters.encodePlanGroups(pass);
    pass.setPipeline(this.markBlocks);
    pass.setBindGroup(0, this.common);
    pass.setBindGroup(1, this.markBlocksGroup);
    this.parts.ids.bind(pass, 2);
    pass.dispatchWorkgroupsIndirect(counters.buffer, Counters.offset(A.groupBlocks));
    pass.end();
    const entries = counters.count('groupBlocks');
    scan.encode(encoder, { input: this.blockMask, output: this.blockOffsets, count: entries, totalOut: counters.count('active') });
    compact.encode(encoder, {
      mask: this.blockMask,
      offsets: this.blockOffsets,
      values: this.blockIds,
      output: this.activeIds,
      count: entries,
    });
  }

  /** The per-block (min, max) ranges, 2 f32 per block id (a stream's raster order, a pool's ids; waits for the GPU). */
  async readBlockRanges(): Promise<Float32Array> {
    return readF32(this.device, this.blockRanges);
  }

  /**
   * A pool's chunk ranges: [min, max] per listed slot over its blocks' ranges
   * (the decoded values inside the volume, as the surface reads them; the
   * empty range [FLT_MAX, -FLT_MAX] for a slot without a finite value),
   * reduced on the GPU (slot-ranges.ts: 8 bytes read back per slot). When no
   * read is in flight the work is submitted before this returns.
   */
  readSlotRanges(slots: readonly number[]): Promise<Float32Array> {
    if (!this.slotRanges) return Promise.resolve(new Float32Array(2 * slots.length));
    return this.slotRanges.read(slots);
  }

  /** Bytes held (fixed per volume). */
  get byteSize(): number {
    return this.buffers().reduce((n, b) => n + b.size, 0) + (this.slotRanges?.byteSize ?? 0);
  }

  private buffers(): GPUBuffer[] {
    const u = this.chunkUpdate;
    return [
      this.blockRanges,
      this.neighbourhoodRanges,
      this.groupRanges,
      this.groupMask,
      this.groupOffsets,
      this.activeGroupIds,
      this.blockMask,
      this.blockOffsets,
      this.blockIds,
      this.activeIds,
      this.groupParams,
      ...(u ? [u.decodeParams, u.regionParams, u.groupParams, ...(u.list ? [u.list] : [])] : []),
    ];
  }

  destroy(): void {
    this.chunkUpdate?.changes.close();
    this.slotRanges?.destroy();
    for (const b of this.buffers()) b.destroy();
  }
}

interface ActiveLayouts {
  neighbourhood: GPUBindGroupLayout;
  region: GPUBindGroupLayout;
  common: GPUBindGroupLayout;
  load: GPUBindGroupLayout;
  markGroups: GPUBindGroupLayout;
  markBlocks: GPUBindGroupLayout;
  changed: GPUBindGroupLayout;
}

interface ChunkUpdate {
  pool: ChunkedVolume;
  /** This surface's log of (slot, chunk) changes (ChunkedVolume.changeLog). */
  changes: ReturnType<ChunkedVolume['changeLog']>;
  /** (slot, chunk) pairs, listEntries long; made on first use and when it must grow. */
  list: GPUBuffer | null;
  listEntries: number;
  decodeParams: GPUBuffer;
  regionParams: GPUBuffer;
  groupParams: GPUBuffer;
  neighbourhood: GPUComputePipeline;
  groups: GPUComputePipeline;
  neighbourhoodGroup: GPUBindGroup;
  regionGroup: GPUBindGroup | null;
  loadGroup: GPUBindGroup;
  changedGroup: GPUBindGroup | null;
  layouts: ActiveLayouts;
  words: Uint32Array<ArrayBuffer>;
}

/** 2 f32 per block, all [FLT_MAX, -FLT_MAX]: no isovalue falls in them. */
function emptyRanges(device: GPUDevice, blocks: number): GPUBuffer {
  const buffer = device.createBuffer({
    label: 'Isosurface.blockRanges',
    size: Math.max(8, blocks * 8),
    usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST,
    mappedAtCreation: true,
  });
  const f = new Float32Array(buffer.getMappedRange());
  for (let i = 0; i < f.length; i += 2) {
    f[i] = 3.4028234663852886e38;
    f[i + 1] = -3.4028234663852886e38;
  }
  buffer.unmap();
  return buffer;
}
