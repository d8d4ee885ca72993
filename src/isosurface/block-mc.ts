// Block marching cubes over the cached blocks (docs/design.md, steps 4-5), in work
// proportional to the surface (shaders/isosurface/block_*.wgsl):
//   classify_blocks  one invocation per active block classifies its 64 cells
//                    once: case codes (per slot), index, welded-vertex and
//                    emitting-cell counts
//   scans            of the three counts -> each block's first index, first
//                    vertex and first cell, and the totals
//   plan_vertices    overflow check, expansion and shard arguments, draw args
//   expand_cells     the emitting-cell list (record, first index), and per
//                    slot the first vertex of each row of cells
//   emit_surface     one invocation per emitting cell, per index shard: the
//                    vertices of the cut edges it owns, its triangles' indices
// So the vertex pass runs once per emitting cell, not once per cell of every
// active block, each block's voxels are classified once, and each vertex is
// computed once (edge_owner.wgsl), however many triangles share it.
import { createCaseTableBuffer } from '../mc/case-table-wgsl.ts';
import type { ExclusiveScan } from '../primitives/scan.ts';
import { Counters } from './counters.ts';
import { bindGroup, bufferLayout, storageBuffer } from '../gpu/bindings.ts';
import { createComputePipeline } from '../gpu/pipeline-cache.ts';
import { A, C, CELL_RECORD_BYTES } from './layout.ts';
import { SurfaceOutput } from './vertex-output.ts';
import type { BlockIds } from './block-ids.ts';
import { isosurfaceWgsl } from './wgsl.ts';

export interface BlockMcParts {
  volume: GPUBuffer;
  counters: Counters;
  scan: ExclusiveScan;
  activeIds: GPUBuffer;
  blockToSlot: GPUBuffer;
  maxWorkgroupsPerDimension: number;
  /** maxStorageBufferBindingSize: the cell list is two bindings of 4 bytes per cell. */
  maxBindingBytes: number;
  /** How blocks are named (block-ids.ts). */
  ids: BlockIds;
}

/** Bytes per cache slot of the per-slot and per-active-block buffers: per row of 4 cells its case bytes and row base (32 words), 6 counts/offsets. */
export const MC_BYTES_PER_SLOT = 152;

/** The regions of the block counts and offsets buffers (block_classify.wgsl). */
const INDICES = 0;
const WELDED = 1;
const CELLS = 2;

/** Words per region: the capacity rounded up to 64 (count_stride in common.wgsl). */
function countStride(capacity: number): number {
  return Math.ceil(capacity / 64) * 64;
}

/** Region k of a counts or offsets buffer, as a binding. */
function region(e: { capacity: number; stride: number }, buffer: GPUBuffer, k: number): GPUBufferBinding {
  return { buffer, offset: k * e.stride * 4, size: Math.max(4, e.capacity * 4) };
}

/** Entries of the emitting-cell list for `vertices` vertices (every emitting cell has >= 3, but a ghost chunk's: indicesForCells). */
export function cellCapacityFor(vertices: number, maxBindingBytes = Infinity): number {
  return Math.max(1, Math.min(Math.floor(vertices / 3) + 1, Math.floor(maxBindingBytes / 4)));
}

/**
 * The index capacity whose cell list holds `cells` entries (cellCapacityFor).
 * A pool's ghost chunks (ChunkedVolume.setRoles) list cells that write
 * vertices but no index, so the cell list may overflow while the indices fit.
 */
export function indicesForCells(cells: number): number {
  return 3 * Math.max(0, cells - 1);
}

/** Bytes of the emitting-cell list for a vertex capacity (counted with the vertex output). */
export function cellBytesFor(vertices: number, maxBindingBytes = Infinity): number {
  return cellCapacityFor(vertices, maxBindingBytes) * CELL_RECORD_BYTES;
}

interface EntryBuffers {
  capacity: number;
  /** Per slot, per row (y, z) of 4 cells: 4 case bytes, then the row base (block_classify.wgsl, block_expand.wgsl). */
  slotMc: GPUBuffer;
  /** Per active entry, three regions of `stride` words: triangle corners, welded vertices, emitting cells (block_classify.wgsl). */
  counts: GPUBuffer;
  /** Their exclusive scans, in the same three regions. */
  offsets: GPUBuffer;
  /** Words per region: the capacity rounded up to 64 (256-byte binding offsets; count_stride in common.wgsl). */
  stride: number;
}

interface CellBuffers {
  capacity: number;
  /** Per emitting cell: (entry << 6 | cell, with CELL_NO_INDICES for a cell that writes only its vertices; first index). */
  list: GPUBuffer;
}

interface Layouts {
  common: GPUBindGroupLayout;
  classify: GPUBindGroupLayout;
  expand: GPUBindGroupLayout;
  cells: GPUBindGroupLayout;
  shard: GPUBindGroupLayout;
  plan: GPUBindGroupLayout;
}

interface Groups {
  slotData: GPUBuffer;
  shards: SurfaceOutput['shards'];
  vertices: GPUBuffer;
  common: GPUBindGroup;
  classify: GPUBindGroup;
  expand: GPUBindGroup;
  cells: GPUBindGroup;
  plan: GPUBindGroup;
  shardGroups: GPUBindGroup[];
}

export class BlockMarchingCubes {
  private entries: EntryBuffers;
  private cells: CellBuffers;
  private groups?: Groups;
  private readonly caseTable: GPUBuffer;
  /** classify_blocks' atomic count of occupied blocks, copied to counters.occupied. */
  private readonly occupied: GPUBuffer;

  private constructor(
    private readonly device: GPUDevice,
    private readonly parts: BlockMcParts,
    private readonly layouts: Layouts,
    private readonly classifyPipeline: GPUComputePipeline,
    private readonly expandPipeline: GPUComputePipeline,
    private readonly emitPipeline: GPUComputePipeline,
    private readonly planPipeline: GPUComputePipeline,
    capacity: number,
    vertexCapacity: number,
  ) {
    this.caseTable = createCaseTableBuffer(device, GPUBufferUsage.UNIFORM);
    this.occupied = storageBuffer(device, 'Isosurface.occupiedCount', 4, GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST);
    this.entries = this.allocateEntries(capacity);
    this.cells = this.allocateCells(vertexCapacity);
  }

  static async create(device: GPUDevice, parts: BlockMcParts, capacity: number, vertexCapacity: number): Promise<BlockMarchingCubes> {
    const layouts: Layouts = {
      common: bufferLayout(device, 'Isosurface.blockMc.layout', ['uniform', 'uniform', 'read', 'read', 'read']),
      classify: bufferLayout(device, 'Isosurface.classifyBlocks.layout', ['uniform', 'rw', 'rw', 'rw']),
      expand: bufferLayout(device, 'Isosurface.expandCells.layout', [
        'uniform',
        'uniform',
        'rw',
        'read',
        'read',
        'rw',
        'read',
        'read',
        'uniform',
      ]),
      cells: bufferLayout(device, 'Isosurface.emitSurface.layout', ['read', 'read']),
      shard: bufferLayout(device, 'Isosurface.shard.layout', ['uniform', 'rw', 'rw']),
      plan: bufferLayout(device, 'Isosurface.planVertices.layout', ['rw', 'read', 'read', 'read', 'read', 'rw', 'rw']),
    };
    const constants = { MAX_WG_PER_DIM: parts.maxWorkgroupsPerDimension };
    const { ids } = parts;
    const [classify, expand, emit, plan] = await Promise.all([
      createComputePipeline(device, 'Isosurface.classifyBlocks', [...isosurfaceWgsl.blockClassify, ids.part], 'classify_blocks', {
        layout: ids.layouts([layouts.common, layouts.classify]),
        constants,
      }),
      createComputePipeline(device, 'Isosurface.expandCells', [...isosurfaceWgsl.blockExpand, ids.part], 'expand_cells', {
        layout: ids.layouts([layouts.expand]),
        constants,
      }),
      createComputePipeline(device, 'Isosurface.emitSurface', [...isosurfaceWgsl.blockEmit, ids.part], 'emit_surface', {
        layout: ids.layouts([layouts.common, layouts.cells, layouts.shard]),
        constants,
      }),
      createComputePipeline(device, 'Isosurface.planVertices', isosurfaceWgsl.plan, 'plan_vertices', { layout: [layouts.plan], constants }),
    ]);
    return new BlockMarchingCubes(device, parts, layouts, classify, expand, emit, plan, capacity, vertexCapacity);
  }

  /** The per-entry counts of the last surface (region 0: triangle corners per active entry; readback only). */
  get blockCounts(): GPUBuffer {
    return this.entries.counts;
  }

  private allocateEntries(capacity: number): EntryBuffers {
    const words = (label: string, perEntry = 1) => storageBuffer(this.device, `Isosurface.${label}`, capacity * 4 * perEntry);
    const stride = countStride(capacity);
    return {
      capacity,
      slotMc: words('slotMc', 32),
      counts: storageBuffer(this.device, 'Isosurface.blockCounts', 3 * stride * 4, GPUBufferUsage.COPY_SRC),
      offsets: storageBuffer(this.device, 'Isosurface.blockOffsets', 3 * stride * 4),
      stride,
    };
  }

  private allocateCells(vertexCapacity: number): CellBuffers {
    const capacity = cellCapacityFor(vertexCapacity, this.parts.maxBindingBytes);
    this.parts.counters.set('cellCapacity', capacity);
    return { capacity, list: storageBuffer(this.device, 'Isosurface.cellList', capacity * CELL_RECORD_BYTES) };
  }

  private destroyEntries(e: EntryBuffers): void {
    for (const b of [e.slotMc, e.counts, e.offsets]) b.destroy();
  }

  /** Per-active-block buffers and the case table (counted with the cache). */
  get byteSize(): number {
    return this.entries.capacity * MC_BYTES_PER_SLOT + this.caseTable.size;
  }

  /** The emitting-cell list (counted with the vertex output). */
  get cellBytes(): number {
    return this.cells.capacity * CELL_RECORD_BYTES;
  }

  /** Per-active-block buffers for `capacity` active blocks (the cache's slot count). Call between submissions. */
  resize(capacity: number): void {
    if (capacity === this.entries.capacity) return;
    this.destroyEntries(this.entries);
    this.entries = this.allocateEntries(capacity);
    this.groups = undefined;
  }

  /** The cell list for a new vertex capacity. Call between submissions. */
  resizeCells(vertexCapacity: number): void {
    const capacity = cellCapacityFor(vertexCapacity, this.parts.maxBindingBytes);
    if (capacity === this.cells.capacity) return;
    this.cells.list.destroy();
    this.cells = this.allocateCells(vertexCapacity);
    this.groups = undefined;
  }

  /** Bind groups for the current cache slot data and vertex shards (rebuilt only when they change). */
  private bind(slotData: GPUBuffer, shards: SurfaceOutput): Groups {
    const g = this.groups;
    if (g && g.slotData === slotData && g.shards === shards.shards && g.vertices === shards.vertices) return g;
    const d = this.device;
    const p = this.parts;
    const e = this.entries;
    const c = this.cells;
    const L = this.layouts;
    const counters = p.counters.buffer;
    this.groups = {
      slotData,
      shards: shards.shards,
      vertices: shards.vertices,
      common: bindGroup(d, 'Isosurface.blockMc.bindGroup', L.common, [p.volume, this.caseTable, slotData, p.blockToSlot, p.activeIds]),
      classify: bindGroup(d, 'Isosurface.classifyBlocks.bindGroup', L.classify, [counters, e.slotMc, e.counts, this.occupied]),
      expand: bindGroup(d, 'Isosurface.expandCells.bindGroup', L.expand, [
        this.caseTable,
        counters,
        e.slotMc,
        region(e, e.counts, CELLS),
        e.offsets,
        c.list,
        p.activeIds,
        p.blockToSlot,
        p.volume,
      ]),
      cells: bindGroup(d, 'Isosurface.emitSurface.bindGroup', L.cells, [c.list, e.slotMc]),
      plan: bindGroup(d, 'Isosurface.planVertices.bindGroup', L.plan, [
        counters,
        region(e, e.offsets, INDICES),
        region(e, e.counts, INDICES),
        region(e, e.offsets, CELLS),
        region(e, e.counts, CELLS),
        shards.shardInfo,
        shards.drawArgs,
      ]),
      shardGroups: shards.shards.map((s, k) =>
        bindGroup(d, `Isosurface.shard${k}.bindGroup`, L.shard, [shards.shardRecord(k), s.indices, shards.vertices]),
      ),
    };
    return this.groups;
  }

  /** Records classify_blocks over the active blocks (case codes, vertex and cell counts, occupied count). */
  encodeClassify(encoder: GPUCommandEncoder, slotData: GPUBuffer, shards: SurfaceOutput): void {
    const g = this.bind(slotData, shards);
    const { counters } = this.parts;
    encoder.clearBuffer(this.occupied);
    const pass = encoder.beginComputePass({ label: 'Isosurface.classifyBlocks' });
    pass.setPipeline(this.classifyPipeline);
    pass.setBindGroup(0, g.common);
    pass.setBindGroup(1, g.classify);
    this.parts.ids.bind(pass, 2);
    pass.dispatchWorkgroupsIndirect(counters.buffer, Counters.offset(A.mark));
    pass.end();
    encoder.copyBufferToBuffer(this.occupied, 0, counters.buffer, Counters.offset(C.occupied), 4);
  }

  /** Records the scans of the index, welded-vertex and cell counts (-> offsets and the totals). */
  encodeScans(encoder: GPUCommandEncoder): void {
    const { counters, scan } = this.parts;
    const e = this.entries;
    const active = counters.count('activeGated');
    const scanOf = (k: number, total: 'vertices' | 'welded' | 'cells') =>
      scan.encode(encoder, {
        input: region(e, e.counts, k),
        output: region(e, e.offsets, k),
        count: active,
        totalOut: counters.count(total),
      });
    scanOf(INDICES, 'vertices');
    scanOf(WELDED, 'welded');
    scanOf(CELLS, 'cells');
  }

  /** Records plan_vertices: overflow check, expansion and shard arguments, draw arguments. */
  encodePlanVertices(encoder: GPUCommandEncoder, slotData: GPUBuffer, shards: SurfaceOutput): void {
    const g = this.bind(slotData, shards);
    const pass = encoder.beginComputePass({ label: 'Isosurface.planVertices' });
    pass.setPipeline(this.planPipeline);
    pass.setBindGroup(0, g.plan);
    pass.dispatchWorkgroups(1);
    pass.end();
  }

  /** Records expand_cells: the emitting-cell list (dispatch sized by plan_vertices, 0 when the surface does not fit). */
  encodeCellList(encoder: GPUCommandEncoder, slotData: GPUBuffer, shards: SurfaceOutput): void {
    const g = this.bind(slotData, shards);
    const pass = encoder.beginComputePass({ label: 'Isosurface.expandCells' });
    pass.setPipeline(this.expandPipeline);
    pass.setBindGroup(0, g.expand);
    this.parts.ids.bind(pass, 1);
    pass.dispatchWorkgroupsIndirect(this.parts.counters.buffer, Counters.offset(A.expand));
    pass.end();
  }

  /** Records the vertex pass (vertices and indices) of every index shard (each dispatch sized on the GPU). */
  encodeVertices(encoder: GPUCommandEncoder, slotData: GPUBuffer, shards: SurfaceOutput): void {
    const g = this.bind(slotData, shards);
    const pass = encoder.beginComputePass({ label: 'Isosurface.emitSurface' });
    pass.setPipeline(this.emitPipeline);
    pass.setBindGroup(0, g.common);
    pass.setBindGroup(1, g.cells);
    this.parts.ids.bind(pass, 3);
    for (let k = 0; k < shards.shards.length; k++) {
      pass.setBindGroup(2, g.shardGroups[k]);
      pass.dispatchWorkgroupsIndirect(shards.shardInfo, SurfaceOutput.dispatchArgsOffset(k));
    }
    pass.end();
  }

  destroy(): void {
    this.destroyEntries(this.entries);
    this.cells.list.destroy();
    this.caseTable.destroy();
    this.occupied.destroy();
  }
}
