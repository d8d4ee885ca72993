// Block marching cubes over the cached blocks (DESIGN.md steps 4-6), in
// fewer passes than the paper: one pass over the active blocks gives each
// block's vertex count (0 = not occupied), a scan of the counts gives every
// block's output offset and the total, a scan + ID compaction of "count > 0"
// gives the occupied list, and one vertex pass per shard runs over the
// occupied blocks whose output reaches that shard (shaders/isosurface/block_mc.wgsl).
import { createCaseTableBuffer } from '../mc/case-table-wgsl.ts';
import type { StreamCompactIds } from '../primitives/compact.ts';
import type { ExclusiveScan } from '../primitives/scan.ts';
import { Counters } from './counters.ts';
import { bindGroup, bindGroupLayout, computePipeline, storageBuffer } from './gpu-util.ts';
import { A } from './layout.ts';
import { VertexShards } from './vertex-output.ts';
import { isosurfaceWgsl } from './wgsl.ts';

export interface BlockMcParts {
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
  emit: GPUBindGroupLayout;
  shard: GPUBindGroupLayout;
  plan: GPUBindGroupLayout;
}

interface Groups {
  slotData: GPUBuffer;
  shards: VertexShards['shards'];
  common: GPUBindGroup;
  count: GPUBindGroup;
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
    private readonly emitPipeline: GPUComputePipeline,
    private readonly planPipeline: GPUComputePipeline,
    capacity: number,
  ) {
    this.caseTable = createCaseTableBuffer(device, GPUBufferUsage.UNIFORM);
    this.entries = this.allocate(capacity);
  }

  static async create(device: GPUDevice, parts: BlockMcParts, capacity: number): Promise<BlockMarchingCubes> {
    const layouts: Layouts = {
      common: bindGroupLayout(device, 'Isosurface.blockMc.layout', ['uniform', 'uniform', 'read', 'read', 'read']),
      count: bindGroupLayout(device, 'Isosurface.countVertices.layout', ['read', 'rw', 'rw']),
      emit: bindGroupLayout(device, 'Isosurface.emitVertices.layout', ['read', 'read']),
      shard: bindGroupLayout(device, 'Isosurface.shard.layout', ['read', 'rw']),
      plan: bindGroupLayout(device, 'Isosurface.planVertices.layout', ['rw', 'read', 'read', 'read', 'rw', 'rw']),
    };
    const constants = { MAX_WG_PER_DIM: parts.maxWorkgroupsPerDimension };
    const [count, emit, plan] = await Promise.all([
      computePipeline(device, 'Isosurface.countVertices', isosurfaceWgsl.blockMc, 'count_vertices', [layouts.common, layouts.count], constants),
      computePipeline(device, 'Isosurface.emitVertices', isosurfaceWgsl.blockMc, 'emit_vertices', [layouts.common, layouts.emit, layouts.shard], constants),
      computePipeline(device, 'Isosurface.planVertices', isosurfaceWgsl.plan, 'plan_vertices', [layouts.plan], constants),
    ]);
    return new BlockMarchingCubes(device, parts, layouts, count, emit, plan, capacity);
  }

  private allocate(capacity: number): EntryBuffers {
    const words = (label: string) => storageBuffer(this.device, `Isosurface.${label}`, capacity * 4);
    return {
      capacity,
      vertexCounts: words('vertexCounts'),
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
      count: bindGroup(d, 'Isosurface.countVertices.bindGroup', L.count, [p.counters.buffer, e.vertexCounts, e.occupiedMask]),
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
    let pass = encoder.beginComputePass({ label: 'Isosurface.countVertices' });
    pass.setPipeline(this.countPipeline);
    pass.setBindGroup(0, g.common);
    pass.setBindGroup(1, g.count);
    pass.dispatchWorkgroupsIndirect(counters.buffer, Counters.offset(A.mc));
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
