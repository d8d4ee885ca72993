// The isosurface pipeline of one volume: its parts (created once per volume,
// from pipelines cached per device) and the passes of one surface, recorded
// into a caller's command encoder with no readback:
//   ActiveBlocks (active-blocks.ts)   chunk updates, neighbourhood ranges, active list
//   BlockCache (lru-cache.ts)         Algorithm 1 and the decode into slots
//   BlockMarchingCubes (block-mc.ts)  classification, counts, offsets, vertices
//   SurfaceOutput (vertex-output.ts)  welded vertices, indices in <= 1-binding shards, draw args
// plus growth of the cache and the vertex output within a budget, and the
// draw data the renderer binds. Scheduling (newest wins, surfaces in flight,
// error scopes, statistics) is isosurface.ts's.
import type { GpuContext } from '../gpu/device.ts';
import { readU32 } from '../gpu/buffers.ts';
import { StreamCompact, StreamCompactIds } from '../primitives/compact.ts';
import { ExclusiveScan } from '../primitives/scan.ts';
import { ZfpDecoder } from '../zfp/decoder.ts';
import type { BlockSource } from '../zfp/gpu-stream.ts';
import { blockIdsOf, type BlockIds } from './block-ids.ts';
import { ActiveBlocks, groupGrid } from './active-blocks.ts';
import { BlockMarchingCubes, indicesForCells } from './block-mc.ts';
import { cacheBytesFor, formatMB, grownCapacity, maxCacheSlots, vertexBytesFor, weldedFor } from './budget.ts';
import { Counters } from './counters.ts';
import {
  C,
  COUNTER_WORDS,
  DEFAULT_GROUP_EDGE_BLOCKS,
  DRAW_ARGS_BYTES,
  INDEX_BYTES,
  SLOT_BYTES,
  STATUS_CACHE_SHORTFALL,
  STATUS_VERTEX_OVERFLOW,
  VERTEX_BYTES,
  VOLUME_PARAMS,
} from './layout.ts';
import { BlockCache } from './lru-cache.ts';
import type { StatsReadback } from './stats-readback.ts';
import { IsosurfaceBudgetError, type IsosurfaceDrawData, type IsosurfaceOptions, type SurfaceMesh, type VolumeInfo } from './types.ts';
import { readWeldedMesh, SurfaceOutput } from './vertex-output.ts';
import { surfaceDimsProblem } from '../core/limits.ts';

/** The parts of one volume's pipeline (owned: destroy() frees them, except the stream). */
export interface PipelineParts {
  stream: BlockSource;
  /** VolumeParams (layout.ts VOLUME_PARAMS): dims, block count, block grid, the isovalue. */
  volume: GPUBuffer;
  counters: Counters;
  decoder: ZfpDecoder;
  /** Over the groups and the blocks of active groups. */
  scan: ExclusiveScan;
  /** Sized to the cache slots (cache update, block counts). */
  slotScan: ExclusiveScan;
  compact: StreamCompact;
  compactIds: StreamCompactIds;
  active: ActiveBlocks;
  cache: BlockCache;
  mc: BlockMarchingCubes;
  shards: SurfaceOutput;
  /** How blocks are named: a stream's raster ids, a pool's ids (block-ids.ts). */
  ids: BlockIds;
}

/** What one surface's passes need besides the parts. */
export interface SurfacePasses {
  iso: number;
  /** Written into the counters (C.request): the statistics carry it. */
  requestId: number;
  /** Only the vertex planning and output (resuming after a vertex overflow). */
  verticesOnly: boolean;
  /** Timestamps between the stages. */
  marks: StatsReadback;
}

export class IsosurfacePipeline {
  readonly drawData: IsosurfaceDrawData;
  private readonly isoWord = new Float32Array(1);

  private constructor(
    readonly gpu: GpuContext,
    readonly parts: PipelineParts,
    readonly info: VolumeInfo,
    /** Cache slots at creation (resetCache returns to them). */
    readonly initialSlots: number,
    /** Slots whose data fits one storage binding (the cache never grows beyond). */
    readonly maxSlots: number,
    /** Welded vertices that fit one binding (the vertex buffer never grows beyond). */
    readonly maxWelded: number,
    /** Only the cache: no triangles (IsosurfaceOptions.cacheOnly). */
    readonly cacheOnly: boolean,
  ) {
    this.drawData = {
      vertices: parts.shards.vertices,
      shards: parts.shards.drawShards,
      info,
      slotData: parts.cache.slotData,
      blockToSlot: parts.cache.blockToSlot,
      neighbourhoodRanges: parts.active.neighbourhoodRanges,
      version: 0,
    };
  }

  /**
   * Builds the pipeline for one volume within `budget` bytes of cache and
   * vertex buffers: block ranges and their neighbourhood ranges (one GPU pass
   * at load, read back once for info.valueRange; a pool starts empty, so its
   * value range is the store's, which the caller knows), the cache at its
   * initial capacity and the vertex shards. `stream`: a whole zfp stream, or
   * one level of a chunked store (ChunkedVolume: the groups of the
   * active-block selection are its chunks).
   */
  static async create(gpu: GpuContext, stream: BlockSource, options: IsosurfaceOptions, budget: number): Promise<IsosurfacePipeline> {
    const { device } = gpu;
    const limits = device.limits;
    const maxWg = options.maxWorkgroupsPerDimension ?? limits.maxComputeWorkgroupsPerDimension;
    const { blockGrid, dims } = stream.info;
    const tooWide = surfaceDimsProblem(dims);
    if (tooWide) throw new RangeError(`${stream.info.fileName}: ${tooWide}`);
    // Per-block buffers hold one entry per block id: a stream's blocks, a pool's slots x blocks per chunk (block-ids.ts).
    const ids = blockIdsOf(device, stream);
    const blockCount = ids.count;
    const bindingBytes = Math.min(options.maxVertexBindingBytes ?? Infinity, limits.maxStorageBufferBindingSize, limits.maxBufferSize);
    const perShard = Math.floor(bindingBytes / INDEX_BYTES);
    // The welded vertices are one binding (every index shard draws from them).
    const maxWelded = Math.floor(Math.min(limits.maxStorageBufferBindingSize, limits.maxBufferSize) / VERTEX_BYTES);
    if (perShard < 1) throw new RangeError(`maxVertexBindingBytes must hold at least one index (${INDEX_BYTES} bytes)`);
    const maxSlots = maxCacheSlots(limits, options.maxStorageBindingBytes);
    let slots = Math.max(1, Math.min(blockCount, maxSlots, options.initialCacheSlots ?? Math.ceil(blockCount / 10)));
    // a cache-only surface makes no triangles: its vertex buffers stay at their smallest
    let vertices = options.cacheOnly
      ? 1
      : Math.max(1, options.initialVertexCapacity ?? Math.min(2 ** 22, Math.max(2 ** 16, blockCount * 8)));
    // The initial buffers must fit the budget too: shrink both (keeping their
    // ratio) until they do; the per-block and per-shard bytes do not shrink.
    const cacheOnly = options.cacheOnly ?? false;
    const bytesAt = (s: number, v: number) =>
      cacheBytesFor(s, blockCount, cacheOnly) + vertexBytesFor(v, Math.min(maxWelded, weldedFor(v)), perShard);
    if (bytesAt(slots, vertices) > budget) {
      const smallest = bytesAt(1, 1);
      if (smallest > budget) {
        throw new IsosurfaceBudgetError(
          `${stream.info.fileName}: the smallest cache and vertex buffers need ${formatMB(smallest)}, the budget is ${formatMB(budget)}; raise it`,
          smallest,
          budget,
        );
      }
      // Largest scale factor in (0, 1] that fits, by bisection on the factor.
      let lo = 0;
      let hi = 1;
      for (let i = 0; i < 40; i++) {
        const f = (lo + hi) / 2;
        if (bytesAt(Math.max(1, Math.floor(slots * f)), Math.max(1, Math.floor(vertices * f))) <= budget) lo = f;
        else hi = f;
      }
      slots = Math.max(1, Math.floor(slots * lo));
      vertices = Math.max(1, Math.floor(vertices * lo));
    }

    const pool = ids.pool;
    const groupEdge = pool ? pool.chunkBlocks : (options.groupEdgeBlocks ?? DEFAULT_GROUP_EDGE_BLOCKS);
    if (!Number.isInteger(groupEdge) || groupEdge < 1 || groupEdge > 64)
      throw new RangeError(`groupEdgeBlocks must be an integer in 1..64 (got ${groupEdge})`);
    // a pool's groups are its slots
    const groupEntries = pool ? blockCount : groupGrid(blockGrid, groupEdge).reduce((a, b) => a * b, 1) * groupEdge ** 3;
    // Per-block buffers are bound whole too: neighbourhood ranges (8 B per block), the group-grid lists (4 B per entry).
    const perBlockBinding = Math.max(blockCount * 8, groupEntries * 4);
    const storageBinding = Math.min(options.maxStorageBindingBytes ?? Infinity, limits.maxStorageBufferBindingSize, limits.maxBufferSize);
    if (perBlockBinding > storageBinding) {
      throw new RangeError(
        `${stream.info.fileName}: ${blockCount} blocks need ${formatMB(perBlockBinding)} per-block buffers in one storage binding; ` +
          `this device binds at most ${formatMB(storageBinding)} (maxStorageBufferBindingSize)`,
      );
    }
    const volume = device.createBuffer({
      label: 'Isosurface.volume',
      size: VOLUME_PARAMS.bytes,
      usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
    });
    device.queue.writeBuffer(volume, 0, new Uint32Array([...dims, blockCount, ...blockGrid, 0]));
    const primitiveOptions = { maxWorkgroupsPerDimension: maxWg, path: options.primitivePath };
    // Two scans: one over the groups and the blocks of active groups, one
    // sized to the cache slots for the cache update and the block counts, so
    // their levels (dispatches) follow the cache, not the volume.
    const [counters, decoder, scan, slotScan, compact, compactIds] = await Promise.all([
      Counters.create(device, maxWg),
      ZfpDecoder.create(device, { ...primitiveOptions, path: options.zfpDecoderPath ?? options.primitivePath }),
      ExclusiveScan.create(device, { capacity: groupEntries, ...primitiveOptions }),
      ExclusiveScan.create(device, { capacity: slots, ...primitiveOptions }),
      StreamCompact.create(device, primitiveOptions),
      StreamCompactIds.create(device, primitiveOptions),
    ]);
    counters.set('blocks', blockCount);
    const active = await ActiveBlocks.create(device, {
      stream,
      decoder,
      volume,
      counters,
      scan,
      compact,
      compactIds,
      maxWorkgroupsPerDimension: maxWg,
      groupEdge,
      ids,
    });
    // A pool starts empty: its value range is the store's (the caller knows it), not the blocks'.
    const [cache, ranges] = await Promise.all([
      BlockCache.create(
        device,
        {
          stream,
          decoder,
          counters,
          scan: slotScan,
          compact,
          compactIds,
          activeIds: active.activeIds,
          maxWorkgroupsPerDimension: maxWg,
          blockIds: blockCount,
        },
        slots,
      ),
      pool ? new Float32Array(0) : active.readBlockRanges(),
    ]);
    const mc = await BlockMarchingCubes.create(
      device,
      {
        volume,
        counters,
        scan: slotScan,
        activeIds: active.activeIds,
        blockToSlot: cache.blockToSlot,
        maxWorkgroupsPerDimension: maxWg,
        maxBindingBytes: limits.maxStorageBufferBindingSize,
        ids,
      },
      cacheOnly ? 1 : slots,
      vertices,
    );
    const shards = new SurfaceOutput(device, perShard, vertices, Math.min(maxWelded, weldedFor(vertices)));
    let lo = Infinity;
    let hi = -Infinity;
    for (let b = 0; b < ranges.length / 2; b++) {
      lo = Math.min(lo, ranges[2 * b]);
      hi = Math.max(hi, ranges[2 * b + 1]);
    }
    if (pool) [lo, hi] = [0, 0];
    const info: VolumeInfo = { dims: [...dims], blockGrid: [...blockGrid], blockCount, valueRange: [lo, hi] };
    const pipeline = new IsosurfacePipeline(
      gpu,
      { stream, volume, counters, decoder, scan, slotScan, compact, compactIds, active, cache, mc, shards, ids },
      info,
      slots,
      maxSlots,
      maxWelded,
      options.cacheOnly ?? false,
    );
    pipeline.writeShardCounters();
    return pipeline;
  }

  private get device(): GPUDevice {
    return this.gpu.device;
  }

  /** Records the passes of one surface into `encoder` (the caller submits). */
  encode(encoder: GPUCommandEncoder, a: SurfacePasses): void {
    const { device } = this;
    const { active, counters, cache, mc, shards } = this.parts;
    const s = a.marks;
    this.isoWord[0] = a.iso;
    device.queue.writeBuffer(this.parts.volume, VOLUME_PARAMS.isoOffset, this.isoWord);
    counters.set('request', a.requestId);
    s.mark(encoder, 0);
    if (!a.verticesOnly) {
      active.encodeChunkUpdates(encoder, (pass, list, params, count) =>
        cache.encodeForget(pass, list, params, count, this.parts.ids.pool?.blocksPerChunk ?? 1),
      );
      active.encode(encoder);
      const pass = encoder.beginComputePass({ label: 'Isosurface.planCache' });
      counters.encodePlanCache(pass);
      pass.end();
    }
    s.mark(encoder, 1);
    if (!a.verticesOnly) cache.encodeUpdate(encoder);
    s.mark(encoder, 2);
    if (!a.verticesOnly) cache.encodeDecode(encoder);
    s.mark(encoder, 3);
    // a cache-only surface stops here: the stages after it are timed as nothing
    const mesh = !this.cacheOnly;
    if (mesh && !a.verticesOnly) mc.encodeClassify(encoder, cache.slotData, shards);
    s.mark(encoder, 4);
    if (a.verticesOnly) counters.set('status', 0);
    else if (mesh) mc.encodeScans(encoder);
    if (mesh) mc.encodePlanVertices(encoder, cache.slotData, shards);
    s.mark(encoder, 5);
    if (mesh) mc.encodeCellList(encoder, cache.slotData, shards);
    s.mark(encoder, 6);
    if (mesh) mc.encodeVertices(encoder, cache.slotData, shards);
    s.mark(encoder, 7);
  }

  /** Bytes the cache would take at `slots` slots (budget.ts: cacheBytesFor). */
  cacheBytesFor(slots: number): number {
    return cacheBytesFor(Math.max(1, slots), this.info.blockCount, this.cacheOnly);
  }

  /** Bytes of the cache (slots, maps, per-active buffers). */
  get cacheBytes(): number {
    return this.parts.cache.byteSize + this.parts.mc.byteSize;
  }

  /** Bytes of the vertex output (shards and the emitting-cell list). */
  get vertexBytes(): number {
    return this.parts.shards.byteSize + this.parts.mc.cellBytes;
  }

  /** Bytes outside the budget: the stream (or pool), per-block buffers, counters, uniforms. */
  get fixedBytes(): number {
    const p = this.parts;
    return p.stream.byteSize + p.active.byteSize + p.counters.buffer.size + p.volume.size;
  }

  // ---- growth

  private budgetError(iso: number, slots: number, indices: number, welded: number, need: number, budget: number): IsosurfaceBudgetError {
    const cache = cacheBytesFor(slots, this.info.blockCount, this.cacheOnly);
    const verts = vertexBytesFor(indices, welded, this.parts.shards.perShard);
    return new IsosurfaceBudgetError(
      `the surface at iso ${iso} needs ${formatMB(need)} (cache: ${slots} blocks, ${formatMB(cache)}; ` +
        `triangles: ${Math.floor(indices / 3)}, vertices: ${welded}, ${formatMB(verts)}), ` +
        `the budget is ${formatMB(budget)}; raise it (setMemoryBudget, or --cache-budget MB in the CLI). The previous surface is kept.`,
      need,
      budget,
    );
  }

  private bindingError(iso: number, slots: number): Error {
    return new Error(
      `Isosurface: the surface at iso ${iso} needs ${slots} cache slots (${formatMB(slots * SLOT_BYTES)} of decoded blocks), ` +
        `but this device binds at most ${this.maxSlots} slots (${formatMB(this.maxSlots * SLOT_BYTES)}: maxStorageBufferBindingSize) in one buffer. The previous surface is kept.`,
    );
  }

  private vertexBindingError(iso: number, welded: number): Error {
    return new Error(
      `Isosurface: the surface at iso ${iso} has ${welded} vertices (${formatMB(welded * VERTEX_BYTES)}), ` +
        `but this device binds at most ${this.maxWelded} (${formatMB(this.maxWelded * VERTEX_BYTES)}: maxStorageBufferBindingSize) in one buffer. The previous surface is kept.`,
    );
  }

  /** Grows what the status says was too small, within `budget` (between submissions; nothing in flight). Throws the budget or binding refusal. */
  grow(status: number, c: Uint32Array, iso: number, budget: number): void {
    const blocks = this.info.blockCount;
    const out = this.parts.shards;
    const perShard = out.perShard;
    let slots = this.parts.cache.capacity;
    let indices = out.capacity;
    let welded = out.weldedCapacity;
    let minSlots = slots;
    let minIndices = indices;
    let minWelded = welded;
    if (status & STATUS_CACHE_SHORTFALL) {
      minSlots = c[C.active];
      if (minSlots > this.maxSlots) throw this.bindingError(iso, minSlots);
      slots = grownCapacity(slots, minSlots, Math.min(blocks, this.maxSlots));
    }
    if (status & STATUS_VERTEX_OVERFLOW) {
      // the cell list follows the index capacity; cells without indices (a pool's chunk roles, block_mc_common.wgsl) may overflow it alone
      minIndices = Math.max(indices, c[C.vertices], indicesForCells(c[C.cells]));
      minWelded = Math.max(welded, c[C.welded]);
      if (minWelded > this.maxWelded) throw this.vertexBindingError(iso, minWelded);
      if (minIndices > indices) indices = grownCapacity(indices, minIndices);
      if (c[C.welded] > welded) welded = grownCapacity(welded, minWelded);
      // at least the quarter of the indices a new output starts with
      welded = Math.min(this.maxWelded, Math.max(welded, weldedFor(indices)));
    }
    const bytes = (s: number, i: number, v: number) => cacheBytesFor(s, blocks, this.cacheOnly) + vertexBytesFor(i, v, perShard);
    const need = bytes(minSlots, minIndices, minWelded);
    if (need > budget) throw this.budgetError(iso, minSlots, minIndices, minWelded, need, budget);
    // Headroom only as far as the budget allows.
    if (bytes(slots, indices, welded) > budget) {
      slots = minSlots;
      indices = minIndices;
      welded = minWelded;
    }
    if (slots > this.parts.cache.capacity) {
      // growing keeps the cached blocks by copying them into the larger cache, so the old cache and the
      // new are held at once; where the budget has no room for both, the cache is made anew (the blocks
      // the retry needs are decoded again) and the old one goes first
      const oldCache = cacheBytesFor(this.parts.cache.capacity, blocks, this.cacheOnly);
      if (bytes(slots, indices, welded) + oldCache <= budget) this.parts.cache.grow(slots);
      else this.parts.cache.reset(slots);
      // a cache-only surface classifies nothing: its per-slot classification buffers stay at one slot
      if (!this.cacheOnly) this.parts.mc.resize(slots);
    }
    if (indices > out.capacity) {
      out.resize(indices, Math.max(welded, out.weldedCapacity));
      this.parts.mc.resizeCells(out.capacity);
      this.writeShardCounters();
    } else if (welded > out.weldedCapacity) {
      out.resizeVertices(welded);
      this.writeShardCounters();
    }
    this.refreshDrawData();
  }

  writeShardCounters(): void {
    this.parts.counters.set('vertexCapacity', this.parts.shards.capacity);
    this.parts.counters.set('weldedCapacity', this.parts.shards.weldedCapacity);
    this.parts.counters.set('shards', this.parts.shards.shards.length);
    this.parts.counters.set('perShard', this.parts.shards.perShard);
  }

  refreshDrawData(): void {
    const d = this.drawData;
    const out = this.parts.shards;
    const shards = out.drawShards;
    const changed =
      d.slotData !== this.parts.cache.slotData ||
      d.vertices !== out.vertices ||
      d.shards.length !== shards.length ||
      d.shards.some((s, k) => s.indices !== shards[k].indices || s.drawArgs !== shards[k].drawArgs);
    if (!changed) return;
    d.vertices = out.vertices;
    d.shards = shards;
    d.slotData = this.parts.cache.slotData;
    d.version++;
  }

  /** Empties the cache and returns it to its initial capacity (queue-ordered after work in flight). */
  resetCache(): void {
    this.parts.cache.reset(this.initialSlots);
    if (!this.cacheOnly) this.parts.mc.resize(this.initialSlots);
    this.refreshDrawData();
  }

  // ---- readback (CLI, export): these wait for the GPU

  /** The drawn surface as an indexed mesh: its welded vertices and its indices (shard after shard). */
  async readMesh(): Promise<SurfaceMesh> {
    const { device } = this;
    const out = this.parts.shards;
    const shards = out.shards;
    const [args, counters] = await Promise.all([
      readU32(device, out.drawArgs, 0, (shards.length * DRAW_ARGS_BYTES) / 4),
      readU32(device, this.parts.counters.buffer, 0, COUNTER_WORDS),
    ]);
    const welded = Math.min(counters[C.drawnWelded], out.weldedCapacity);
    const counted = shards.map((s, k) => ({ indices: s.indices, count: args[(DRAW_ARGS_BYTES / 4) * k] }));
    return readWeldedMesh(device, out.vertices, welded, counted, this.info.dims);
  }

  /** Per-block (min, max), 2 f32 per block in raster block order (for the page's block-count profile). */
  readBlockRanges(): Promise<Float32Array> {
    return this.parts.active.readBlockRanges();
  }

  /** A pool's [min, max] per listed slot (ActiveBlocks.readSlotRanges). */
  readSlotRanges(slots: readonly number[]): Promise<Float32Array> {
    return this.parts.active.readSlotRanges(slots);
  }

  /**
   * The drawn surface's triangles per block: the active block ids and, for
   * each, the triangles of the cells whose lowest corner lies in it (the
   * classify pass's counts). A pool's ids name their slot (id / blocks per
   * chunk), so the stream sums them per chunk (the view cut's record).
   */
  async readBlockTriangles(): Promise<{ ids: Uint32Array; triangles: Uint32Array }> {
    const { device } = this;
    const c = await readU32(device, this.parts.counters.buffer, 0, COUNTER_WORDS);
    const n = c[C.activeGated];
    if (n === 0) return { ids: new Uint32Array(0), triangles: new Uint32Array(0) };
    const [ids, corners] = await Promise.all([
      readU32(device, this.parts.active.activeIds, 0, n),
      readU32(device, this.parts.mc.blockCounts, 0, n),
    ]);
    return { ids, triangles: corners.map((k) => k / 3) };
  }

  destroy(): void {
    const p = this.parts;
    p.shards.destroy();
    p.mc.destroy();
    p.cache.destroy();
    p.active.destroy();
    p.compact.destroy();
    p.compactIds.destroy();
    p.scan.destroy();
    p.slotScan.destroy();
    p.decoder.destroy();
    p.counters.destroy();
    p.volume.destroy();
    p.ids.destroy();
  }
}
