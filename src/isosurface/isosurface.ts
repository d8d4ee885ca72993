// One Isosurface per volume: the GPU-driven pipeline from an isovalue to a
// drawable triangle soup (DESIGN.md, paper section 4), composed of
//   ActiveBlocks (active-blocks.ts)   neighbourhood ranges, active list
//   BlockCache (lru-cache.ts)         Algorithm 1 and the decode into slots
//   BlockMarchingCubes (block-mc.ts)  counts, offsets, occupied list, vertices
//   VertexShards (vertex-output.ts)   the soup in <= 1-binding shards, draw args
//   StatsReadback                     counters + timestamps, mapped later
// setIsovalue() records every pass into one submission; every later size
// (dispatches and the draw) comes from GPU-written indirect arguments, and
// nothing on the way waits for the GPU. At most one computation is in flight;
// a newer isovalue replaces a pending one. When the statistics say the cache
// or the vertex buffers were too small (the GPU skipped the work and kept the
// previous surface), the host grows them within the memory budget and
// recomputes that isovalue, unless a newer one is waiting.
import type { GpuContext } from '../gpu/device.ts';
import { readU32 } from '../gpu/buffers.ts';
import { hitRate, type SurfaceEngine } from '../bench/harness.ts';
import { StreamCompact, StreamCompactIds } from '../primitives/compact.ts';
import { ExclusiveScan } from '../primitives/scan.ts';
import { ZfpDecoder } from '../zfp/decoder.ts';
import { isChunked, type ChunkSyncTargets, type IsosurfaceSource } from './source.ts';
import { ActiveBlocks, groupGrid } from './active-blocks.ts';
import { BlockMarchingCubes } from './block-mc.ts';
import { cacheBytesFor, defaultMemoryBudget, formatMB, grownCapacity, vertexBytesFor } from './budget.ts';
import { Counters } from './counters.ts';
import { C, DEFAULT_GROUP_EDGE_BLOCKS, DRAW_ARGS_BYTES, STATUS_CACHE_SHORTFALL, STATUS_VERTEX_OVERFLOW, VERTEX_BYTES } from './layout.ts';
import { BlockCache } from './lru-cache.ts';
import { StatsReadback, type RawStats } from './stats-readback.ts';
import {
  IsosurfaceBudgetError,
  IsosurfaceSupersededError,
  type IsosurfaceDrawData,
  type IsosurfaceOptions,
  type IsosurfaceStats,
  type VolumeInfo,
} from './types.ts';
import { VertexShards } from './vertex-output.ts';

interface Waiter {
  resolve(stats: IsosurfaceStats): void;
  reject(error: Error): void;
}

interface Request {
  iso: number;
  waiters: Waiter[];
  grew: boolean;
  attempts: number;
  /** GPU ms of earlier attempts (skipped for growth). */
  earlierMs: number;
  /** Blocks decoded by earlier attempts (a vertex overflow happens after the cache update). */
  earlierNew: number;
  /** resetCache() count when the last attempt was recorded. */
  cacheEpoch: number;
}

/** Attempts per isovalue: one, plus a cache growth, plus a vertex growth, plus slack. */
const MAX_ATTEMPTS = 4;

function syncTargets(active: ActiveBlocks, cache: BlockCache, counters: Counters): ChunkSyncTargets {
  return {
    blockRanges: active.blockRanges,
    neighbourhoodRanges: active.neighbourhoodRanges,
    groupRanges: active.groupRanges,
    blockToSlot: cache.blockToSlot,
    slotToBlock: cache.slotToBlock,
    slotAge: cache.slotAge,
    counters: counters.buffer,
  };
}

export class Isosurface implements SurfaceEngine {
  readonly info: VolumeInfo;
  readonly drawData: IsosurfaceDrawData;
  private readonly statsListeners = new Set<(stats: IsosurfaceStats) => void>();
  private readonly errorListeners = new Set<(error: Error) => void>();
  private pending?: Request;
  private inFlight?: Request;
  private destroyed = false;
  private budget: number;
  private readonly isoWord = new Float32Array(1);
  private lastStats?: IsosurfaceStats;
  /** Increases with every resetCache(): a vertices-only retry needs the same cache as its attempt. */
  private cacheEpoch = 0;

  private constructor(
    private readonly gpu: GpuContext,
    private readonly stream: IsosurfaceSource,
    private readonly volume: GPUBuffer,
    private readonly counters: Counters,
    private readonly decoder: ZfpDecoder,
    private readonly scan: ExclusiveScan,
    private readonly slotScan: ExclusiveScan,
    private readonly compact: StreamCompact,
    private readonly compactIds: StreamCompactIds,
    private readonly active: ActiveBlocks,
    private readonly cache: BlockCache,
    private readonly mc: BlockMarchingCubes,
    private readonly shards: VertexShards,
    private readonly stats: StatsReadback,
    private readonly initialSlots: number,
    info: VolumeInfo,
    budget: number,
  ) {
    this.info = info;
    this.budget = budget;
    this.drawData = { shards: shards.drawShards, info, slotData: cache.slotData, blockToSlot: cache.blockToSlot, version: 0 };
  }

  /**
   * Builds the pipeline for one volume: pipelines, block ranges and their
   * neighbourhood ranges (one GPU pass at load, read back once for
   * info.valueRange), the cache at its initial capacity and the vertex shards.
   */
  static async create(gpu: GpuContext, stream: IsosurfaceSource, options: IsosurfaceOptions = {}): Promise<Isosurface> {
    if (isChunked(stream)) stream.attach();
    const { device } = gpu;
    const limits = device.limits;
    const maxWg = options.maxWorkgroupsPerDimension ?? limits.maxComputeWorkgroupsPerDimension;
    const { blockCount, blockGrid, dims } = stream.info;
    const budget = options.memoryBudgetBytes ?? defaultMemoryBudget(limits);
    const bindingBytes = Math.min(options.maxVertexBindingBytes ?? Infinity, limits.maxStorageBufferBindingSize, limits.maxBufferSize);
    const perShard = Math.floor(bindingBytes / VERTEX_BYTES);
    if (perShard < 1) throw new RangeError(`maxVertexBindingBytes must hold at least one vertex (${VERTEX_BYTES} bytes)`);
    let slots = Math.max(1, Math.min(blockCount, options.initialCacheSlots ?? Math.ceil(blockCount / 10)));
    let vertices = Math.max(1, options.initialVertexCapacity ?? Math.min(2 ** 22, Math.max(2 ** 16, blockCount * 8)));
    // The initial buffers must fit the budget too: shrink both (keeping their
    // ratio) until they do; the per-block and per-shard bytes do not shrink.
    const bytesAt = (s: number, v: number) => cacheBytesFor(s, blockCount) + vertexBytesFor(v, perShard);
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

    // A chunked source's groups are its chunks.
    const groupEdge = isChunked(stream) ? stream.groupEdgeBlocks : (options.groupEdgeBlocks ?? DEFAULT_GROUP_EDGE_BLOCKS);
    if (!Number.isInteger(groupEdge) || groupEdge < 1 || groupEdge > 64) throw new RangeError(`groupEdgeBlocks must be an integer in 1..64 (got ${groupEdge})`);
    const groupEntries = groupGrid(blockGrid, groupEdge).reduce((a, b) => a * b, 1) * groupEdge ** 3;
    const volume = device.createBuffer({ label: 'Isosurface.volume', size: 32, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
    device.queue.writeBuffer(volume, 0, new Uint32Array([...dims, blockCount, ...blockGrid, 0]));
    const primitiveOptions = { maxWorkgroupsPerDimension: maxWg };
    // Two scans: one over the groups and the blocks of active groups, one
    // sized to the cache slots for the cache update and the block counts, so
    // their levels (dispatches) follow the cache, not the volume.
    const [counters, decoder, scan, slotScan, compact, compactIds] = await Promise.all([
      Counters.create(device, maxWg),
      ZfpDecoder.create(device, primitiveOptions),
      ExclusiveScan.create(device, { capacity: groupEntries, ...primitiveOptions }),
      ExclusiveScan.create(device, { capacity: slots, ...primitiveOptions }),
      StreamCompact.create(device, primitiveOptions),
      StreamCompactIds.create(device, primitiveOptions),
    ]);
    counters.set('blocks', blockCount);
    const active = await ActiveBlocks.create(device, { stream, decoder, volume, counters, scan, compact, compactIds, maxWorkgroupsPerDimension: maxWg, groupEdge });
    const cache = await BlockCache.create(device, { stream, decoder, counters, scan: slotScan, compact, compactIds, activeIds: active.activeIds, maxWorkgroupsPerDimension: maxWg }, slots);
    if (isChunked(stream)) {
      // The chunks put before now: their ranges (so info.valueRange covers them).
      const encoder = device.createCommandEncoder({ label: 'Isosurface.chunkSync' });
      stream.encodeSync(encoder, syncTargets(active, cache, counters));
      device.queue.submit([encoder.finish()]);
    }
    const ranges = await active.readBlockRanges();
    const mc = await BlockMarchingCubes.create(
      device,
      { volume, counters, scan: slotScan, activeIds: active.activeIds, blockToSlot: cache.blockToSlot, maxWorkgroupsPerDimension: maxWg, maxBindingBytes: limits.maxStorageBufferBindingSize },
      slots,
      vertices,
    );
    const shards = new VertexShards(device, perShard, vertices);
    let lo = Infinity;
    let hi = -Infinity;
    for (let b = 0; b < blockCount; b++) {
      lo = Math.min(lo, ranges[2 * b]);
      hi = Math.max(hi, ranges[2 * b + 1]);
    }
    const info: VolumeInfo = { dims: [...dims], blockGrid: [...blockGrid], blockCount, valueRange: [lo, hi] };
    const iso = new Isosurface(gpu, stream, volume, counters, decoder, scan, slotScan, compact, compactIds, active, cache, mc, shards, new StatsReadback(device, options.timing ?? true), slots, info, budget);
    iso.writeShardCounters();
    return iso;
  }

  private get device(): GPUDevice {
    return this.gpu.device;
  }

  // ---- requests: newest wins, at most one in flight

  /** Computes the surface at `iso` (float32) as soon as nothing else is in flight; never waits. */
  setIsovalue(iso: number): void {
    this.request(iso);
  }

  /** Computes the surface at `iso`; resolves with its statistics (for the CLI and the benchmark). */
  compute(iso: number): Promise<IsosurfaceStats> {
    return new Promise((resolve, reject) => this.request(iso, { resolve, reject }));
  }

  /** Statistics of every computed surface; returns an unsubscribe function. */
  onStats(listener: (stats: IsosurfaceStats) => void): () => void {
    this.statsListeners.add(listener);
    return () => this.statsListeners.delete(listener);
  }

  /** Budget refusals and GPU failures; returns an unsubscribe function. */
  onError(listener: (error: Error) => void): () => void {
    this.errorListeners.add(listener);
    return () => this.errorListeners.delete(listener);
  }

  /** The statistics of the surface drawn now, if any. */
  get currentStats(): IsosurfaceStats | undefined {
    return this.lastStats;
  }

  /** True while a computation is on the GPU or waiting. */
  get busy(): boolean {
    return this.inFlight !== undefined || this.pending !== undefined;
  }

  private request(iso: number, waiter?: Waiter): void {
    if (this.destroyed) {
      waiter?.reject(new Error('Isosurface: destroyed'));
      return;
    }
    if (!Number.isFinite(iso)) {
      waiter?.reject(new RangeError(`isovalue ${iso} is not a finite number`));
      return;
    }
    const f = Math.fround(iso);
    const replaced = this.pending;
    if (replaced) for (const w of replaced.waiters) w.reject(new IsosurfaceSupersededError(replaced.iso, f));
    this.pending = { iso: f, waiters: waiter ? [waiter] : [], grew: false, attempts: 0, earlierMs: 0, earlierNew: 0, cacheEpoch: this.cacheEpoch };
    if (!this.inFlight) this.launchPending();
  }

  private launchPending(): void {
    const r = this.pending;
    this.pending = undefined;
    if (r) this.launch(r);
  }

  /**
   * Records and submits the computation of r.iso: one command buffer, no
   * waits. `verticesOnly` resumes after a vertex overflow: the cache update
   * and the block counts of the failed attempt are still in their buffers
   * (nothing ran since), so only plan_vertices and the vertex pass run again.
   */
  private launch(r: Request, verticesOnly = false): void {
    this.inFlight = r;
    r.attempts++;
    r.cacheEpoch = this.cacheEpoch;
    try {
      this.record(r, verticesOnly);
    } catch (e) {
      this.fail(r, e instanceof Error ? e : new Error(String(e)));
    }
  }

  private record(r: Request, verticesOnly: boolean): void {
    const { device } = this;
    this.isoWord[0] = r.iso;
    device.queue.writeBuffer(this.volume, 28, this.isoWord);
    const encoder = device.createCommandEncoder({ label: 'Isosurface.compute' });
    const s = this.stats;
    s.mark(encoder, 0);
    if (!verticesOnly) {
      // Chunks put or evicted since the last surface: their ranges, their
      // neighbours' neighbourhood and group ranges, their cached blocks.
      if (isChunked(this.stream)) this.stream.encodeSync(encoder, syncTargets(this.active, this.cache, this.counters));
      this.active.encode(encoder);
      const pass = encoder.beginComputePass({ label: 'Isosurface.planCache' });
      this.counters.encodePlanCache(pass);
      pass.end();
    }
    s.mark(encoder, 1);
    if (!verticesOnly) this.cache.encodeUpdate(encoder);
    s.mark(encoder, 2);
    if (!verticesOnly) this.cache.encodeDecode(encoder);
    s.mark(encoder, 3);
    if (!verticesOnly) this.mc.encodeClassify(encoder, this.cache.slotData, this.shards);
    s.mark(encoder, 4);
    if (verticesOnly) this.counters.set('status', 0);
    else this.mc.encodeScans(encoder);
    this.mc.encodePlanVertices(encoder, this.cache.slotData, this.shards);
    s.mark(encoder, 5);
    this.mc.encodeCellList(encoder, this.cache.slotData, this.shards);
    s.mark(encoder, 6);
    this.mc.encodeVertices(encoder, this.cache.slotData, this.shards);
    s.mark(encoder, 7);
    const staging = s.encodeCopy(encoder, this.counters.buffer);
    device.queue.submit([encoder.finish()]);
    const submittedAt = performance.now();
    s.read(staging, submittedAt).then(
      (raw) => this.finish(r, raw),
      (e) => this.fail(r, e instanceof Error ? e : new Error(String(e))),
    );
  }

  private finish(r: Request, raw: RawStats): void {
    this.inFlight = undefined;
    if (this.destroyed) return;
    const status = raw.counters[C.status];
    if (status !== 0) {
      r.earlierMs += raw.gpuMs;
      // A vertices-only retry reads these counters again; a full one does not.
      // (Only if the cache was not reset while the attempt ran.)
      const verticesOnly = status === STATUS_VERTEX_OVERFLOW && r.cacheEpoch === this.cacheEpoch;
      if (!verticesOnly) r.earlierNew += raw.counters[C.new];
      if (this.pending) {
        // A newer isovalue is waiting: compute that one (it grows what it needs).
        for (const w of r.waiters) w.reject(new IsosurfaceSupersededError(r.iso, this.pending.iso));
        this.launchPending();
        return;
      }
      try {
        if (r.attempts >= MAX_ATTEMPTS) throw new Error(`Isosurface: iso ${r.iso} still does not fit after ${r.attempts} attempts (status ${status})`);
        this.grow(status, raw.counters, r.iso);
      } catch (e) {
        this.fail(r, e as Error);
        return;
      }
      r.grew = true;
      this.launch(r, verticesOnly);
      return;
    }
    const stats = this.toStats(r, raw);
    this.lastStats = stats;
    for (const l of this.statsListeners) l(stats);
    for (const w of r.waiters) w.resolve(stats);
    this.launchPending();
  }

  private fail(r: Request, error: Error): void {
    this.inFlight = undefined;
    if (this.destroyed) return;
    for (const l of this.errorListeners) l(error);
    for (const w of r.waiters) w.reject(error);
    this.launchPending();
  }

  private toStats(r: Request, raw: RawStats): IsosurfaceStats {
    const c = raw.counters;
    const activeBlocks = c[C.active];
    const newBlocks = c[C.new] + r.earlierNew;
    const vertices = c[C.vertices];
    const stages = r.earlierMs > 0 ? [...raw.stages, { label: 'attempts before growth', ms: r.earlierMs }] : raw.stages;
    return {
      isovalue: r.iso,
      activeBlocks,
      newBlocks,
      occupiedBlocks: c[C.occupied],
      hitRate: hitRate(activeBlocks, newBlocks),
      vertices,
      triangles: vertices / 3,
      cacheSlots: this.cache.capacity,
      cacheSlotsUsed: c[C.slotsUsed],
      cacheBytes: this.cache.byteSize + this.mc.byteSize,
      vertexBytes: this.shards.byteSize + this.mc.cellBytes,
      gpuMs: raw.gpuMs + r.earlierMs,
      stages,
      timingSource: raw.source,
      grew: r.grew,
      fixedBytes: (isChunked(this.stream) ? this.stream.poolBytes : this.stream.byteSize) + this.active.byteSize + this.counters.buffer.size + this.volume.size,
    };
  }

  // ---- growth

  private budgetError(iso: number, slots: number, vertices: number, need: number): IsosurfaceBudgetError {
    const cache = cacheBytesFor(slots, this.info.blockCount);
    const verts = vertexBytesFor(vertices, this.shards.perShard);
    return new IsosurfaceBudgetError(
      `the surface at iso ${iso} needs ${formatMB(need)} (cache: ${slots} blocks, ${formatMB(cache)}; vertices: ${vertices}, ${formatMB(verts)}), ` +
        `the budget is ${formatMB(this.budget)}; raise it (setMemoryBudget, or --cache-budget MB in the CLI). The previous surface is kept.`,
      need,
      this.budget,
    );
  }

  /** Grows what the status says was too small (between submissions; nothing in flight). */
  private grow(status: number, c: Uint32Array, iso: number): void {
    const blocks = this.info.blockCount;
    const perShard = this.shards.perShard;
    let slots = this.cache.capacity;
    let vertices = this.shards.capacity;
    let minSlots = slots;
    let minVertices = vertices;
    if (status & STATUS_CACHE_SHORTFALL) {
      minSlots = c[C.active];
      slots = grownCapacity(slots, minSlots, blocks);
    }
    if (status & STATUS_VERTEX_OVERFLOW) {
      minVertices = c[C.vertices];
      vertices = grownCapacity(vertices, minVertices);
    }
    const bytes = (s: number, v: number) => cacheBytesFor(s, blocks) + vertexBytesFor(v, perShard);
    const need = bytes(minSlots, minVertices);
    if (need > this.budget) throw this.budgetError(iso, minSlots, minVertices, need);
    // Headroom only as far as the budget allows.
    if (bytes(slots, vertices) > this.budget) {
      slots = minSlots;
      vertices = minVertices;
    }
    if (slots > this.cache.capacity) {
      this.cache.grow(slots);
      this.mc.resize(slots);
    }
    if (vertices > this.shards.capacity) {
      this.shards.resize(vertices);
      this.mc.resizeCells(vertices);
      this.writeShardCounters();
    }
    this.refreshDrawData();
  }

  private writeShardCounters(): void {
    this.counters.set('vertexCapacity', this.shards.capacity);
    this.counters.set('shards', this.shards.shards.length);
    this.counters.set('perShard', this.shards.perShard);
  }

  private refreshDrawData(): void {
    const d = this.drawData;
    const shards = this.shards.drawShards;
    const changed = d.slotData !== this.cache.slotData || d.shards.length !== shards.length || d.shards.some((s, k) => s.vertices !== shards[k].vertices || s.drawArgs !== shards[k].drawArgs);
    if (!changed) return;
    d.shards = shards;
    d.slotData = this.cache.slotData;
    d.version++;
  }

  // ---- cache and budget

  /**
   * Empties the cache and returns it to its initial capacity (so each
   * benchmark mode starts cold and from the same state). The drawn surface
   * stays drawn. Queue-ordered after any computation in flight.
   */
  resetCache(): void {
    if (this.destroyed) return;
    this.cacheEpoch++;
    this.cache.reset(this.initialSlots);
    this.mc.resize(this.initialSlots);
    this.refreshDrawData();
  }

  /** Bytes the cache and vertex buffers may grow to (applies from the next growth on). */
  setMemoryBudget(bytes: number): void {
    if (!(bytes > 0)) throw new RangeError(`memory budget must be positive (got ${bytes})`);
    this.budget = bytes;
  }

  get memoryBudget(): number {
    return this.budget;
  }

  // ---- readback (tests, CLI, export): these wait for the GPU

  /** The packed (position, block id) pairs of the drawn surface, shard after shard. */
  async readVertices(): Promise<Uint32Array> {
    const { device } = this;
    const shards = this.shards.shards;
    const args = await readU32(device, this.shards.drawArgs, 0, (shards.length * DRAW_ARGS_BYTES) / 4);
    const counts = shards.map((_, k) => args[4 * k]);
    const total = counts.reduce((a, b) => a + b, 0);
    const out = new Uint32Array(2 * total);
    let at = 0;
    for (let k = 0; k < shards.length; k++) {
      if (counts[k] === 0) continue;
      out.set(await readU32(device, shards[k].vertices, 0, 2 * counts[k]), at);
      at += 2 * counts[k];
    }
    return out;
  }

  /** Per-block (min, max), 2 f32 per block in raster block order (for the page's block-count profile). */
  readBlockRanges(): Promise<Float32Array> {
    return this.active.readBlockRanges();
  }

  /** The cache state (tests): slot -> block, block -> slot, slot ages. */
  async readCacheState(): Promise<{ slotToBlock: Uint32Array; blockToSlot: Uint32Array; slotAge: Uint32Array }> {
    const { device } = this;
    const [slotToBlock, blockToSlot, slotAge] = await Promise.all([
      readU32(device, this.cache.slotToBlock, 0, this.cache.capacity),
      readU32(device, this.cache.blockToSlot, 0, this.info.blockCount),
      readU32(device, this.cache.slotAge, 0, this.cache.capacity),
    ]);
    return { slotToBlock, blockToSlot, slotAge };
  }

  destroy(): void {
    if (this.destroyed) return;
    this.destroyed = true;
    const error = new Error('Isosurface: destroyed');
    for (const r of [this.pending, this.inFlight]) for (const w of r?.waiters ?? []) w.reject(error);
    this.pending = undefined;
    this.inFlight = undefined;
    this.stats.destroy();
    this.shards.destroy();
    this.mc.destroy();
    this.cache.destroy();
    this.active.destroy();
    this.compact.destroy();
    this.compactIds.destroy();
    this.scan.destroy();
    this.slotScan.destroy();
    this.decoder.destroy();
    this.counters.destroy();
    this.volume.destroy();
    this.statsListeners.clear();
    this.errorListeners.clear();
  }
}
