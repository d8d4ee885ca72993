// One Isosurface per volume: the GPU-driven pipeline from an isovalue to a
// drawable triangle soup (docs/design.md, paper section 4), composed of
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
import { StreamCompact, StreamCompactIds } from '../primitives/compact.ts';
import { ExclusiveScan } from '../primitives/scan.ts';
import { ZfpDecoder } from '../zfp/decoder.ts';
import type { ChunkedVolume } from '../zfp/chunked-volume.ts';
import type { BlockSource } from '../zfp/gpu-stream.ts';
import { ActiveBlocks, groupGrid } from './active-blocks.ts';
import { BlockMarchingCubes } from './block-mc.ts';
import { cacheBytesFor, defaultMemoryBudget, formatMB, grownCapacity, maxCacheSlots, vertexBytesFor } from './budget.ts';
import { Counters } from './counters.ts';
import { C, DEFAULT_GROUP_EDGE_BLOCKS, DRAW_ARGS_BYTES, SLOT_BYTES, STATUS_CACHE_SHORTFALL, STATUS_VERTEX_OVERFLOW, VERTEX_BYTES } from './layout.ts';
import { BlockCache } from './lru-cache.ts';
import { StatsReadback, type RawStats } from './stats-readback.ts';
import {
  hitRate,
  IsosurfaceBudgetError,
  IsosurfaceGpuError,
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

/** One submission of a request (a request is submitted again after growth). */
interface Attempt {
  r: Request;
  /** Written into the counters (C.request): its statistics must carry it. */
  id: number;
  verticesOnly: boolean;
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

/**
 * Computations on the GPU at once while scrubbing: the next is recorded while
 * the previous one's statistics are still on their way, yet a new isovalue
 * never queues behind more than one older surface.
 */
const DEFAULT_SURFACES_IN_FLIGHT = 2;

/** Attempts per isovalue: one, plus a cache growth, plus a vertex growth, plus slack. */
const MAX_ATTEMPTS = 4;

export class Isosurface {
  readonly info: VolumeInfo;
  readonly drawData: IsosurfaceDrawData;
  private readonly statsListeners = new Set<(stats: IsosurfaceStats) => void>();
  private readonly errorListeners = new Set<(error: Error) => void>();
  private readonly submitListeners = new Set<(iso: number) => void>();
  private pending?: Request;
  /** Submitted attempts whose statistics are not read yet, oldest first. */
  private readonly inFlight: Attempt[] = [];
  private nextId = 1;
  private destroyed = false;
  private budget: number;
  private readonly isoWord = new Float32Array(1);
  private lastStats?: IsosurfaceStats;
  /** Increases with every resetCache(): a vertices-only retry needs the same cache as its attempt. */
  private cacheEpoch = 0;

  private constructor(
    private readonly gpu: GpuContext,
    private readonly stream: BlockSource,
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
    private readonly maxInFlight: number,
    /** Slots whose data fits one storage binding (the cache never grows beyond). */
    private readonly maxSlots: number,
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
  /**
   * `stream`: a whole zfp stream (ZfpGpuStream), or one level of a chunked
   * store (ChunkedVolume: chunks come and go in a GPU pool; the groups of the
   * active-block selection are its chunks, and a chunk's block ranges are
   * computed on the GPU when it arrives).
   */
  static async create(gpu: GpuContext, stream: BlockSource, options: IsosurfaceOptions = {}): Promise<Isosurface> {
    const { device } = gpu;
    const limits = device.limits;
    const maxWg = options.maxWorkgroupsPerDimension ?? limits.maxComputeWorkgroupsPerDimension;
    const { blockCount, blockGrid, dims } = stream.info;
    const budget = options.memoryBudgetBytes ?? defaultMemoryBudget(limits);
    const bindingBytes = Math.min(options.maxVertexBindingBytes ?? Infinity, limits.maxStorageBufferBindingSize, limits.maxBufferSize);
    const perShard = Math.floor(bindingBytes / VERTEX_BYTES);
    if (perShard < 1) throw new RangeError(`maxVertexBindingBytes must hold at least one vertex (${VERTEX_BYTES} bytes)`);
    const maxSlots = maxCacheSlots(limits, options.maxStorageBindingBytes);
    let slots = Math.max(1, Math.min(blockCount, maxSlots, options.initialCacheSlots ?? Math.ceil(blockCount / 10)));
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

    const maxInFlight = options.maxSurfacesInFlight ?? DEFAULT_SURFACES_IN_FLIGHT;
    if (!Number.isInteger(maxInFlight) || maxInFlight < 1) throw new RangeError(`maxSurfacesInFlight must be a positive integer (got ${maxInFlight})`);
    const pool = stream.addressing === 'pool' ? (stream as ChunkedVolume) : undefined;
    const groupEdge = pool ? pool.chunkBlocks : (options.groupEdgeBlocks ?? DEFAULT_GROUP_EDGE_BLOCKS);
    if (!Number.isInteger(groupEdge) || groupEdge < 1 || groupEdge > 64) throw new RangeError(`groupEdgeBlocks must be an integer in 1..64 (got ${groupEdge})`);
    const groupEntries = groupGrid(blockGrid, groupEdge).reduce((a, b) => a * b, 1) * groupEdge ** 3;
    // Per-block buffers are bound whole too: neighbourhood ranges (8 B per block), the group-grid lists (4 B per entry).
    const perBlockBinding = Math.max(blockCount * 8, groupEntries * 4);
    const storageBinding = Math.min(options.maxStorageBindingBytes ?? Infinity, limits.maxStorageBufferBindingSize, limits.maxBufferSize);
    if (perBlockBinding > storageBinding) {
      throw new RangeError(
        `${stream.info.fileName}: ${blockCount} blocks need ${formatMB(perBlockBinding)} per-block buffers in one storage binding; ` +
          `this device binds at most ${formatMB(storageBinding)} (maxStorageBufferBindingSize)`,
      );
    }
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
    // A pool starts empty: its value range is the store's (the caller knows it), not the blocks'.
    const [cache, ranges] = await Promise.all([
      BlockCache.create(device, { stream, decoder, counters, scan: slotScan, compact, compactIds, activeIds: active.activeIds, maxWorkgroupsPerDimension: maxWg }, slots),
      pool ? new Float32Array(0) : active.readBlockRanges(),
    ]);
    const mc = await BlockMarchingCubes.create(
      device,
      { volume, counters, scan: slotScan, activeIds: active.activeIds, blockToSlot: cache.blockToSlot, maxWorkgroupsPerDimension: maxWg, maxBindingBytes: limits.maxStorageBufferBindingSize },
      slots,
      vertices,
    );
    const shards = new VertexShards(device, perShard, vertices);
    let lo = Infinity;
    let hi = -Infinity;
    for (let b = 0; b < ranges.length / 2; b++) {
      lo = Math.min(lo, ranges[2 * b]);
      hi = Math.max(hi, ranges[2 * b + 1]);
    }
    if (pool) [lo, hi] = [0, 0];
    const info: VolumeInfo = { dims: [...dims], blockGrid: [...blockGrid], blockCount, valueRange: [lo, hi] };
    const iso = new Isosurface(gpu, stream, volume, counters, decoder, scan, slotScan, compact, compactIds, active, cache, mc, shards, new StatsReadback(device, options.timing ?? true), slots, info, budget, maxInFlight, maxSlots);
    iso.writeShardCounters();
    return iso;
  }

  private get device(): GPUDevice {
    return this.gpu.device;
  }

  // ---- requests: newest wins, a bounded number in flight

  /** Computes the surface at `iso` (float32): submitted at once unless `maxSurfacesInFlight` are on the GPU; never waits. */
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

  /**
   * Called right after a computation is submitted: a frame drawn from then on
   * shows its surface (the draw reads GPU-written arguments), so a renderer
   * requests a frame here rather than waiting for the statistics.
   */
  onSubmit(listener: (iso: number) => void): () => void {
    this.submitListeners.add(listener);
    return () => this.submitListeners.delete(listener);
  }

  /** The statistics of the surface drawn now, if any. */
  get currentStats(): IsosurfaceStats | undefined {
    return this.lastStats;
  }

  /** True while a computation is on the GPU or waiting. */
  get busy(): boolean {
    return this.inFlight.length > 0 || this.pending !== undefined;
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
    this.pump();
  }

  /** Submits the pending request if fewer than maxSurfacesInFlight are on the GPU. */
  private pump(): void {
    while (this.pending && this.inFlight.length < this.maxInFlight && !this.destroyed) {
      const r = this.pending;
      this.pending = undefined;
      this.launch(r, false);
    }
  }

  /**
   * Records and submits one attempt at r.iso: one command buffer, no waits,
   * inside validation and out-of-memory error scopes that are popped
   * asynchronously with the statistics. `prepare` (growth) runs inside the
   * scopes too. `verticesOnly` resumes after a vertex overflow: the cache
   * update and the block counts of the failed attempt are still in their
   * buffers (nothing was submitted since), so only plan_vertices and the
   * vertex pass run again.
   */
  private launch(r: Request, verticesOnly: boolean, prepare?: () => void): void {
    const { device } = this;
    const a: Attempt = { r, id: this.nextId++ >>> 0, verticesOnly };
    r.attempts++;
    this.inFlight.push(a);
    device.pushErrorScope('out-of-memory');
    device.pushErrorScope('validation');
    let staging: GPUBuffer | undefined;
    let thrown: Error | undefined;
    try {
      prepare?.();
      r.cacheEpoch = this.cacheEpoch;
      staging = this.record(a);
    } catch (e) {
      thrown = e instanceof Error ? e : new Error(String(e));
    }
    const validation = device.popErrorScope();
    const oom = device.popErrorScope();
    const submittedAt = performance.now();
    if (!thrown) {
      for (const l of this.submitListeners) {
        try {
          l(r.iso);
        } catch (e) {
          queueMicrotask(() => {
            throw e;
          });
        }
      }
    }
    void this.settle(a, staging, thrown, validation, oom, submittedAt);
  }

  /** Waits for the attempt's error scopes and statistics (off the critical path) and acts on them. */
  private async settle(a: Attempt, staging: GPUBuffer | undefined, thrown: Error | undefined, validation: Promise<GPUError | null>, oom: Promise<GPUError | null>, submittedAt: number): Promise<void> {
    const raw = staging ? this.stats.read(staging, submittedAt).catch((e: unknown) => (e instanceof Error ? e : new Error(String(e)))) : undefined;
    let v: GPUError | null;
    let m: GPUError | null;
    try {
      [v, m] = await Promise.all([validation, oom]);
    } catch (e) {
      [v, m] = [null, null];
      thrown ??= e instanceof Error ? e : new Error(String(e));
    }
    const stats = raw ? await raw : undefined;
    if (thrown) return this.fail(a, thrown);
    const gpuError = v ?? m;
    if (gpuError) {
      const kind = v ? 'validation error' : 'out of memory';
      return this.fail(a, new IsosurfaceGpuError(`the computation of the surface at iso ${a.r.iso} failed on the GPU (${kind}: ${gpuError.message.replace(/\s+/g, ' ').trim()}); the previous surface is kept`, a.r.iso));
    }
    if (!stats || stats instanceof Error) return this.fail(a, stats ?? new Error('Isosurface: no statistics'));
    // The staging buffer holds this submission's counters, or it is a failure (never another surface's).
    if (stats.counters[C.request] !== a.id) {
      return this.fail(a, new IsosurfaceGpuError(`the statistics of the surface at iso ${a.r.iso} are not its own (request ${stats.counters[C.request]}, expected ${a.id}): the computation did not run`, a.r.iso));
    }
    this.finish(a, stats);
  }

  private record(a: Attempt): GPUBuffer {
    const { device } = this;
    const { r, verticesOnly } = a;
    this.isoWord[0] = r.iso;
    device.queue.writeBuffer(this.volume, 28, this.isoWord);
    this.counters.set('request', a.id);
    const encoder = device.createCommandEncoder({ label: 'Isosurface.compute' });
    const s = this.stats;
    s.mark(encoder, 0);
    if (!verticesOnly) {
      this.active.encodeChunkUpdates(encoder);
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
    try {
      device.queue.submit([encoder.finish()]);
    } catch (e) {
      s.release(staging);
      throw e;
    }
    return staging;
  }

  private settled(a: Attempt): boolean {
    const i = this.inFlight.indexOf(a);
    if (i >= 0) this.inFlight.splice(i, 1);
    return !this.destroyed;
  }

  private finish(a: Attempt, raw: RawStats): void {
    if (!this.settled(a)) return;
    const r = a.r;
    const status = raw.counters[C.status];
    if (status !== 0) {
      r.earlierMs += raw.gpuMs;
      // A vertices-only retry reads these counters again; a full one does not.
      // (Only if nothing was submitted since and the cache was not reset.)
      const verticesOnly = status === STATUS_VERTEX_OVERFLOW && r.cacheEpoch === this.cacheEpoch && a.id === ((this.nextId - 1) >>> 0);
      if (!verticesOnly) r.earlierNew += raw.counters[C.new];
      const newer = this.pending ?? this.inFlight[this.inFlight.length - 1]?.r;
      if (newer) {
        // A newer isovalue is waiting or already on the GPU (submitted with
        // the same capacities: it grows what it needs if it fails too).
        for (const w of r.waiters) w.reject(new IsosurfaceSupersededError(r.iso, newer.iso));
        this.pump();
        return;
      }
      if (r.attempts >= MAX_ATTEMPTS) {
        this.fail(a, new Error(`Isosurface: iso ${r.iso} still does not fit after ${r.attempts} attempts (status ${status})`), false);
        return;
      }
      r.grew = true;
      // Nothing is in flight now: growth replaces buffers between submissions.
      this.launch(r, verticesOnly, () => this.grow(status, raw.counters, r.iso));
      return;
    }
    const stats = this.toStats(r, raw);
    this.lastStats = stats;
    for (const l of this.statsListeners) l(stats);
    for (const w of r.waiters) w.resolve(stats);
    this.pump();
  }

  private fail(a: Attempt, error: Error, remove = true): void {
    if (remove && !this.settled(a)) return;
    if (this.destroyed) return;
    for (const l of this.errorListeners) l(error);
    for (const w of a.r.waiters) w.reject(error);
    this.pump();
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
      fixedBytes: this.stream.byteSize + this.active.byteSize + this.counters.buffer.size + this.volume.size,
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

  private bindingError(iso: number, slots: number): Error {
    return new Error(
      `Isosurface: the surface at iso ${iso} needs ${slots} cache slots (${formatMB(slots * SLOT_BYTES)} of decoded blocks), ` +
        `but this device binds at most ${this.maxSlots} slots (${formatMB(this.maxSlots * SLOT_BYTES)}: maxStorageBufferBindingSize) in one buffer. The previous surface is kept.`,
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
      if (minSlots > this.maxSlots) throw this.bindingError(iso, minSlots);
      slots = grownCapacity(slots, minSlots, Math.min(blocks, this.maxSlots));
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
    const { device } = this;
    device.pushErrorScope('out-of-memory');
    device.pushErrorScope('validation');
    this.cacheEpoch++;
    this.cache.reset(this.initialSlots);
    this.mc.resize(this.initialSlots);
    this.refreshDrawData();
    const validation = device.popErrorScope();
    const oom = device.popErrorScope();
    void Promise.all([validation, oom]).then(([v, m]) => {
      const e = v ?? m;
      if (!e || this.destroyed) return;
      const error = new IsosurfaceGpuError(`emptying the block cache failed on the GPU (${v ? 'validation error' : 'out of memory'}: ${e.message.replace(/\s+/g, ' ').trim()})`, NaN);
      for (const l of this.errorListeners) l(error);
    });
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

  /** The normals of the drawn surface (u32 octahedral per vertex, vertex_format.wgsl), in readVertices' order. */
  async readNormals(): Promise<Uint32Array> {
    const { device } = this;
    const shards = this.shards.shards;
    const args = await readU32(device, this.shards.drawArgs, 0, (shards.length * DRAW_ARGS_BYTES) / 4);
    const counts = shards.map((_, k) => args[4 * k]);
    const out = new Uint32Array(counts.reduce((a, b) => a + b, 0));
    let at = 0;
    for (let k = 0; k < shards.length; k++) {
      if (counts[k] === 0) continue;
      out.set(await readU32(device, shards[k].normals, 0, counts[k]), at);
      at += counts[k];
    }
    return out;
  }

  /** Per-block (min, max), 2 f32 per block in raster block order (for the page's block-count profile). */
  readBlockRanges(): Promise<Float32Array> {
    return this.active.readBlockRanges();
  }

  /** The cache state (tests): slot -> block, block -> slot, and the LRU order (slots, least recently used first). */
  async readCacheState(): Promise<{ slotToBlock: Uint32Array; blockToSlot: Uint32Array; lruOrder: Uint32Array }> {
    const { device } = this;
    const lru = this.cache.lruLog;
    const [slotToBlock, blockToSlot, log, valid] = await Promise.all([
      readU32(device, this.cache.slotToBlock, 0, this.cache.capacity),
      readU32(device, this.cache.blockToSlot, 0, this.info.blockCount),
      readU32(device, lru.log, 0, lru.size),
      readU32(device, lru.valid, 0, lru.size),
    ]);
    return { slotToBlock, blockToSlot, lruOrder: log.filter((_, p) => valid[p] === 1) };
  }

  destroy(): void {
    if (this.destroyed) return;
    this.destroyed = true;
    const error = new Error('Isosurface: destroyed');
    for (const r of [this.pending, ...this.inFlight.map((a) => a.r)]) for (const w of r?.waiters ?? []) w.reject(error);
    this.pending = undefined;
    this.inFlight.length = 0;
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
    this.submitListeners.clear();
  }
}
