// Block marching cubes over the cached blocks (DESIGN.md steps 4-6), in
// fewer passes than the paper: one pass over the active blocks gives each
// block's vertex count (0 = not occupied), a scan of the counts gives every
// block's output offset and the total, a scan + ID compaction of "count > 0"
// gives the occupied list, and one vertex pass per shard runs over the
// occupied blocks whose output reaches that shard.
//
// Two ways to read a block's voxels, the same results (shaders/isosurface/):
// 'workgroup' (block_mc_workgroup.wgsl) stages the block and its +x/+y/+z
// neighbour voxels in workgroup memory, the paper's design; 'direct'
// (block_mc_direct.wgsl) lets each invocation read its 8 corners from the
// cache, with no workgroup memory in the count pass, which measured several
// times faster on SwiftShader (README.md).
import { createCaseTableBuffer } from '../mc/case-table-wgsl.ts';
import type { StreamCompactIds } from '../primitives/compact.ts';
import type { ExclusiveScan } from '../primitives/scan.ts';
import { Counters } from './counters.ts';
import { bindGroup, bindGroupLayout, computePipeline, storageBuffer } from './gpu-util.ts';
import { A } from './layout.ts';
import { VertexShards } from './vertex-output.ts';
import { isosurfaceWgsl } from './wgsl.ts';

export type BlockLoad = 'workgroup' | 'direct';

export interface BlockMcParts {
  load: BlockLoad;
  volume: GPUBuffer;
  counters: Counters;
  scan: ExclusiveScan;
  compactIds: StreamCompactIds;
  activeIds: GPUBuffer;
  blockToSlot: GPUBuffer;
  maxWorkgroupsPerDimension: number;
}

/** Bytes per cache slot of the per-active-block buffers (5 u32 per entry). */
export const MC_BYTES_PER_SLOT = 20;

interface EntryBuffers {
  capacity: number;
  vertexCounts: GPUBuffer;
  vertexOffsets: GPUBuffer;
  occupiedMask: GPUBuffer;
  occupiedOffsets: GPUBuffer;
  occupiedList: GPUBuffer;
}

interface Layouts {
  common: GPUBindGroupLayout;
  count: GPUBindGroupLayout;
  occupancy: GPUBindGroupLayout;
  emit: GPUBindGroupLayout;
  shard: GPUBindGroupLayout;
  plan: GPUBindGroupLayout;
}

interface Groups {
  slotData: GPUBuffer;
  shards: VertexShards['shards'];
  common: GPUBindGroup;
  count: GPUBindGroup;
  occupancy: GPUBindGroup;
  emit: GPUBindGroup;
  plan: GPUBindGroup;
  shardGroups: GPUBindGroup[];
}

export class BlockMarchingCubes {
  private entries: EntryBuffers;
  private groups?: Groups;
  private readonly caseTable: GPUBuffer;

  private constructor(
    private readonly device: GPUDevice,
    private readonly parts: BlockMcParts,
    private readonly layouts: Layouts,
    private readonly countPipeline: GPUComputePipeline,
    /** 'direct' only: occupancy from the counts. */
    private readonly occupancyPipeline: GPUComputePipeline | undefined,
    private readonly emitPipeline: GPUComputePipeline,
    private readonly planPipeline: GPUComputePipeline,
    capacity: number,
  ) {
    this.caseTable = createCaseTableBuffer(device, GPUBufferUsage.UNIFORM);
    this.entries = this.allocate(capacity);
  }

  static async create(device: GPUDevice, parts: BlockMcParts, capacity: number): Promise<BlockMarchingCubes> {
    const direct = parts.load === 'direct';
    const layouts: Layouts = {
      common: bindGroupLayout(device, 'Isosurface.blockMc.layout', ['uniform', 'uniform', 'read', 'read', 'read']),
      count: bindGroupLayout(device, 'Isosurface.countVertices.layout', direct ? ['read', 'rw'] : ['read', 'rw', 'rw']),
      occupancy: bindGroupLayout(device, 'Isosurface.occupancy.layout', ['read', 'read', 'rw']),
      emit: bindGroupLayout(device, 'Isosurface.emitVertices.layout', ['read', 'read']),
      shard: bindGroupLayout(device, 'Isosurface.shard.layout', ['read', 'rw']),
      plan: bindGroupLayout(device, 'Isosurface.planVertices.layout', ['rw', 'read', 'read', 'read', 'rw', 'rw']),
    };
    const constants = { MAX_WG_PER_DIM: parts.maxWorkgroupsPerDimension };
    const wgsl = direct ? isosurfaceWgsl.blockMcDirect : isosurfaceWgsl.blockMcWorkgroup;
    const suffix = direct ? '_direct' : '';
    const [count, occupancy, emit, plan] = await Promise.all([
      computePipeline(device, 'Isosurface.countVertices', wgsl, `count_vertices${suffix}`, [layouts.common, layouts.count], constants),
      direct ? computePipeline(device, 'Isosurface.occupancy', wgsl, 'occupied_from_counts', [layouts.common, layouts.occupancy], constants) : undefined,
      computePipeline(device, 'Isosurface.emitVertices', wgsl, `emit_vertices${suffix}`, [layouts.common, layouts.emit, layouts.shard], constants),
      computePipeline(device, 'Isosurface.planVertices', isosurfaceWgsl.plan, 'plan_vertices', [layouts.plan], constants),
    ]);
    return new BlockMarchingCubes(device, parts, layouts, count, occupancy, emit, plan, capacity);
  }

  private allocate(capacity: number): EntryBuffers {
    const words = (label: string) => storageBuffer(this.device, `Isosurface.${label}`, capacity * 4);
    return {
      capacity,
      // cleared before each count pass in the 'direct' variant (atomic sums)
      vertexCounts: storageBuffer(this.device, 'Isosurface.vertexCounts', capacity * 4, GPUBufferUsage.COPY_DST),
      vertexOffsets: words('vertexOffsets'),
      occupiedMask: words('occupiedMask'),
      occupiedOffsets: words('occupiedOffsets'),
      occupiedList: words('occupiedList'),
    };
  }

  private destroyEntries(e: EntryBuffers): void {
    for (const b of [e.vertexCounts, e.vertexOffsets, e.occupiedMask, e.occupiedOffsets, e.occupiedList]) b.destroy();
  }

  get byteSize(): number {
    return this.entries.capacity * MC_BYTES_PER_SLOT + this.caseTable.size;
  }

  /** Per-active-block buffers for `capacity` active blocks (the cache's slot count). Call between submissions. */
  resize(capacity: number): void {
    if (capacity === this.entries.capacity) return;
    this.destroyEntries(this.entries);
    this.entries = this.allocate(capacity);
    this.groups = undefined;
  }

  /** Bind groups for the current cache slot data and vertex shards (rebuilt only when they change). */
  private bind(slotData: GPUBuffer, shards: VertexShards): Groups {
    const g = this.groups;
    if (g && g.slotData === slotData && g.shards === shards.shards) return g;
    const d = this.device;
    const p = this.parts;
    const e = this.entries;
    const L = this.layouts;
    this.groups = {
      slotData,
      shards: shards.shards,
      common: bindGroup(d, 'Isosurface.blockMc.bindGroup', L.common, [p.volume, this.caseTable, slotData, p.blockToSlot, p.activeIds]),
      count: bindGroup(d, 'Isosurface.countVertices.bindGroup', L.count, p.load === 'direct' ? [p.counters.buffer, e.vertexCounts] : [p.counters.buffer, e.vertexCounts, e.occupiedMask]),
      occupancy: bindGroup(d, 'Isosurface.occupancy.bindGroup', L.occupancy, [p.counters.buffer, e.vertexCounts, e.occupiedMask]),
      emit: bindGroup(d, 'Isosurface.emitVertices.bindGroup', L.emit, [e.occupiedList, e.vertexOffsets]),
      plan: bindGroup(d, 'Isosurface.planVertices.bindGroup', L.plan, [p.counters.buffer, e.occupiedList, e.vertexOffsets, e.vertexCounts, shards.shardInfo, shards.drawArgs]),
      shardGroups: shards.shards.map((s, k) => bindGroup(d, `Isosurface.shard${k}.bindGroup`, L.shard, [shards.shardRecord(k), s.vertices])),
    };
    return this.groups;
  }

  /**
   * Records the count pass, the scans of counts and occupancy, the occupied
   * list, and plan_vertices (overflow check, shard ranges, draw arguments).
   */
  encodeCounts(encoder: GPUCommandEncoder, slotData: GPUBuffer, shards: VertexShards): void {
    const g = this.bind(slotData, shards);
    const { counters, scan, compactIds } = this.parts;
    const e = this.entries;
    if (this.occupancyPipeline) encoder.clearBuffer(e.vertexCounts);
    const pass = encoder.beginComputePass({ label: 'Isosurface.countVertices' });
    pass.setPipeline(this.countPipeline);
    pass.setBindGroup(0, g.common);
    pass.setBindGroup(1, g.count);
    pass.dispatchWorkgroupsIndirect(counters.buffer, Counters.offset(A.mc));
    if (this.occupancyPipeline) {
      // one invocation per active entry: the mark pass's arguments
      pass.setPipeline(this.occupancyPipeline);
      pass.setBindGroup(1, g.occupancy);
      pass.dispatchWorkgroupsIndirect(counters.buffer, Counters.offset(A.mark));
    }
    pass.end();
    const active = counters.count('activeGated');
    scan.encode(encoder, { input: e.vertexCounts, output: e.vertexOffsets, count: active, totalOut: counters.count('vertices') });
    scan.encode(encoder, { input: e.occupiedMask, output: e.occupiedOffsets, count: active, totalOut: counters.count('occupied') });
    compactIds.encode(encoder, { mask: e.occupiedMask, offsets: e.occupiedOffsets, output: e.occupiedList, count: active });
    this.encodePlanVertices(encoder, slotData, shards);
  }

  /** Records plan_vertices alone (after a vertex overflow, once the shards have grown). */
  encodePlanVertices(encoder: GPUCommandEncoder, slotData: GPUBuffer, shards: VertexShards): void {
    const g = this.bind(slotData, shards);
    const pass = encoder.beginComputePass({ label: 'Isosurface.planVertices' });
    pass.setPipeline(this.planPipeline);
    pass.setBindGroup(0, g.plan);
    pass.dispatchWorkgroups(1);
    pass.end();
  }

  /** Records the vertex pass of every shard (each dispatch sized on the GPU). */
  encodeVertices(encoder: GPUCommandEncoder, slotData: GPUBuffer, shards: VertexShards): void {
    const g = this.bind(slotData, shards);
    const pass = encoder.beginComputePass({ label: 'Isosurface.emitVertices' });
    pass.setPipeline(this.emitPipeline);
    pass.setBindGroup(0, g.common);
    pass.setBindGroup(1, g.emit);
    for (let k = 0; k < shards.shards.length; k++) {
      pass.setBindGroup(2, g.shardGroups[k]);
      pass.dispatchWorkgroupsIndirect(shards.shardInfo, VertexShards.dispatchArgsOffset(k));
    }
    pass.end();
  }

  destroy(): void {
    this.destroyEntries(this.entries);
    this.caseTable.destroy();
  }
}
