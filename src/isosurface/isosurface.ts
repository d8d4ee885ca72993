// One Isosurface per volume: the scheduler over its pipeline (pipeline.ts),
// from an isovalue to a drawable triangle soup (docs/design.md, paper
// section 4). setIsovalue() records every pass into one submission; every
// later size (dispatches and the draw) comes from GPU-written indirect
// arguments, and nothing on the way waits for the GPU. Up to
// maxSurfacesInFlight computations are on the GPU; a newer isovalue replaces
// a pending one (newest wins). Each submission sits in validation and
// out-of-memory error scopes, and its statistics (StatsReadback: counters and
// timestamps, mapped later) carry its request id, so a failure is reported,
// never a stale surface. When the statistics say the cache or the vertex
// buffers were too small (the GPU skipped the work and kept the previous
// surface), the pipeline grows them within the memory budget and the
// isovalue is recomputed, unless a newer one is waiting.
import type { GpuContext } from '../gpu/device.ts';
import type { BlockSource } from '../zfp/gpu-stream.ts';
import { defaultMemoryBudget } from './budget.ts';
import { C, STATUS_VERTEX_OVERFLOW } from './layout.ts';
import { IsosurfacePipeline } from './pipeline.ts';
import { SurfaceSnapshot } from './snapshot.ts';
import { StatsReadback, type RawStats } from './stats-readback.ts';
import {
  hitRate,
  IsosurfaceGpuError,
  IsosurfaceSupersededError,
  type IsosurfaceDrawData,
  type IsosurfaceOptions,
  type IsosurfaceStats,
  type SurfaceMesh,
  type VolumeInfo,
} from './types.ts';

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
  private lastStats?: IsosurfaceStats;
  /** Increases with every resetCache(): a vertices-only retry needs the same cache as its attempt. */
  private cacheEpoch = 0;
  /** present(): the copy of the last computed surface that is drawn (snapshot.ts). */
  private snapshot: SurfaceSnapshot | null = null;

  private constructor(
    private readonly gpu: GpuContext,
    /** The passes and buffers (tests read its parts through tests/helpers/isosurface-readback.ts). */
    readonly pipeline: IsosurfacePipeline,
    private readonly stats: StatsReadback,
    budget: number,
    private readonly maxInFlight: number,
  ) {
    this.info = pipeline.info;
    this.drawData = pipeline.drawData;
    this.budget = budget;
  }

  /**
   * `stream`: a whole zfp stream (ZfpGpuStream), or one level of a chunked
   * store (ChunkedVolume: chunks come and go in a GPU pool; the groups of the
   * active-block selection are its chunks, and a chunk's block ranges are
   * computed on the GPU when it arrives).
   */
  static async create(gpu: GpuContext, stream: BlockSource, options: IsosurfaceOptions = {}): Promise<Isosurface> {
    const maxInFlight = options.maxSurfacesInFlight ?? DEFAULT_SURFACES_IN_FLIGHT;
    if (!Number.isInteger(maxInFlight) || maxInFlight < 1)
      throw new RangeError(`maxSurfacesInFlight must be a positive integer (got ${maxInFlight})`);
    const budget = options.memoryBudgetBytes ?? defaultMemoryBudget(gpu.device.limits);
    const pipeline = await IsosurfacePipeline.create(gpu, stream, options, budget);
    return new Isosurface(gpu, pipeline, new StatsReadback(gpu.device, options.timing ?? true), budget, maxInFlight);
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
    this.pending = {
      iso: f,
      waiters: waiter ? [waiter] : [],
      grew: false,
      attempts: 0,
      earlierMs: 0,
      earlierNew: 0,
      cacheEpoch: this.cacheEpoch,
    };
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
  private async settle(
    a: Attempt,
    staging: GPUBuffer | undefined,
    thrown: Error | undefined,
    validation: Promise<GPUError | null>,
    oom: Promise<GPUError | null>,
    submittedAt: number,
  ): Promise<void> {
    const raw = staging
      ? this.stats.read(staging, submittedAt).catch((e: unknown) => (e instanceof Error ? e : new Error(String(e))))
      : undefined;
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
      return this.fail(
        a,
        new IsosurfaceGpuError(
          `the computation of the surface at iso ${a.r.iso} failed on the GPU (${kind}: ${gpuError.message.replace(/\s+/g, ' ').trim()}); the previous surface is kept`,
          a.r.iso,
        ),
      );
    }
    if (!stats || stats instanceof Error) return this.fail(a, stats ?? new Error('Isosurface: no statistics'));
    // The staging buffer holds this submission's counters, or it is a failure (never another surface's).
    if (stats.counters[C.request] !== a.id) {
      return this.fail(
        a,
        new IsosurfaceGpuError(
          `the statistics of the surface at iso ${a.r.iso} are not its own (request ${stats.counters[C.request]}, expected ${a.id}): the computation did not run`,
          a.r.iso,
        ),
      );
    }
    this.finish(a, stats);
  }

  private record(a: Attempt): GPUBuffer {
    const encoder = this.device.createCommandEncoder({ label: 'Isosurface.compute' });
    this.pipeline.encode(encoder, { iso: a.r.iso, requestId: a.id, verticesOnly: a.verticesOnly, marks: this.stats });
    const staging = this.stats.encodeCopy(encoder, this.pipeline.parts.counters.buffer);
    try {
      this.device.queue.submit([encoder.finish()]);
    } catch (e) {
      this.stats.release(staging);
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
      const verticesOnly = status === STATUS_VERTEX_OVERFLOW && r.cacheEpoch === this.cacheEpoch && a.id === (this.nextId - 1) >>> 0;
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
      this.launch(r, verticesOnly, () => this.pipeline.grow(status, raw.counters, r.iso, this.budget));
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
    const indices = c[C.vertices];
    const stages = r.earlierMs > 0 ? [...raw.stages, { label: 'attempts before growth', ms: r.earlierMs }] : raw.stages;
    return {
      isovalue: r.iso,
      activeBlocks,
      newBlocks,
      occupiedBlocks: c[C.occupied],
      hitRate: hitRate(activeBlocks, newBlocks),
      vertices: c[C.welded],
      indices,
      triangles: indices / 3,
      cacheSlots: this.pipeline.parts.cache.capacity,
      cacheSlotsUsed: c[C.slotsUsed],
      cacheBytes: this.pipeline.cacheBytes,
      cacheBytesNeeded: Math.min(this.pipeline.cacheBytes, this.pipeline.cacheBytesFor(activeBlocks)),
      vertexBytes: this.pipeline.vertexBytes,
      gpuMs: raw.gpuMs + r.earlierMs,
      stages,
      timingSource: raw.source,
      grew: r.grew,
      fixedBytes: this.pipeline.fixedBytes,
    };
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
    this.pipeline.resetCache();
    const validation = device.popErrorScope();
    const oom = device.popErrorScope();
    void Promise.all([validation, oom]).then(([v, m]) => {
      const e = v ?? m;
      if (!e || this.destroyed) return;
      const error = new IsosurfaceGpuError(
        `emptying the block cache failed on the GPU (${v ? 'validation error' : 'out of memory'}: ${e.message.replace(/\s+/g, ' ').trim()})`,
        NaN,
      );
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

  /** Empties the cache to its first size, keeping the drawn surface (resetCache; a stream's surface that gives memory back). */
  trimCache(): void {
    this.resetCache();
  }

  /** Bytes the cache and vertex buffers hold now (what the budget caps); 0 once released or destroyed. */
  get budgetedBytes(): number {
    return this.destroyed ? 0 : this.pipeline.cacheBytes + this.pipeline.vertexBytes;
  }

  // ---- snapshots (a view stream's steps): drawn from a copy while the next surface is computed

  /**
   * Copies the last computed surface (on the GPU, in queue order) and draws
   * the copy from now on (`presented`): later computations no longer change
   * what is drawn until present() is called again.
   */
  present(): void {
    if (this.destroyed || !this.lastStats) return;
    this.snapshot ??= new SurfaceSnapshot(this.gpu.device, this.drawData);
    this.snapshot.capture(this.pipeline.parts.shards, this.drawData, this.lastStats);
  }

  /**
   * A copy the caller owns (the page's other surfaces: each drawn from its
   * copy while this one computes the surface being scrubbed); copyInto fills it.
   */
  newCopy(): SurfaceSnapshot {
    return new SurfaceSnapshot(this.gpu.device, this.drawData);
  }

  /**
   * Copies the surface computed last into `copy` (on the GPU, in queue order):
   * call it when compute() resolved and before anything else is requested,
   * so the buffers hold that surface and the counts are its own.
   */
  copyInto(copy: SurfaceSnapshot): void {
    if (this.destroyed || !this.lastStats) throw new Error('Isosurface.copyInto: no surface computed');
    if (this.busy) throw new Error('Isosurface.copyInto: a computation is on its way; wait for compute() first');
    copy.capture(this.pipeline.parts.shards, this.drawData, this.lastStats);
  }

  /** A new copy of the surface computed last (newCopy + copyInto): a store's other surfaces of a step. */
  copy(): SurfaceSnapshot {
    const copy = this.newCopy();
    try {
      this.copyInto(copy);
    } catch (e) {
      copy.destroy();
      throw e;
    }
    return copy;
  }

  /** What present() copied last, or null before the first present(). */
  get presented(): IsosurfaceDrawData | null {
    return this.snapshot?.drawData ?? null;
  }

  /** Bytes the copy holds now (0 before the first present()). */
  get presentedBytes(): number {
    return this.snapshot?.byteSize ?? 0;
  }

  /** Bytes a present() of the last computed surface would hold. */
  get presentBytesNeeded(): number {
    return this.lastStats && !this.destroyed ? SurfaceSnapshot.bytesFor(this.lastStats, this.pipeline.parts.shards.perShard) : 0;
  }

  /**
   * Lets go of everything but the drawn copy (present()): the pipeline, its
   * cache, vertices and per-block state. The copy stays drawable (its
   * vertices carry positions and normals) until destroy(); the surface can
   * compute nothing more. A stream does this to come within a lowered
   * budget while the step on screen stays drawn.
   */
  release(): void {
    this.#stopWork('Isosurface: released to its drawn copy');
  }

  /** The mesh drawn now: the copy present() made, else the surface itself (readMesh). */
  readDrawnMesh(): Promise<SurfaceMesh> {
    if (this.snapshot) return this.snapshot.readMesh(this.info.dims);
    return this.destroyed ? Promise.reject(new Error('Isosurface: destroyed')) : this.pipeline.readMesh();
  }

  // ---- readback (CLI, export): these wait for the GPU; the tests' own readbacks are in tests/helpers

  /** The packed (position, block id) pairs of the drawn surface, shard after shard. */
  /** The drawn surface as an indexed mesh (welded vertices, indices); waits for the GPU. */
  readMesh(): Promise<SurfaceMesh> {
    return this.pipeline.readMesh();
  }

  /** Per-block (min, max), 2 f32 per block in raster block order (for the page's block-count profile). */
  readBlockRanges(): Promise<Float32Array> {
    return this.pipeline.readBlockRanges();
  }

  /**
   * Over a chunk pool: [min, max] per listed slot of the values its chunk
   * decodes to (padding left out), as of the last computed surface: the
   * ranges a stream learns as chunks arrive. The copies are submitted before
   * this returns (the surface may be destroyed once it has).
   */
  readSlotRanges(slots: readonly number[]): Promise<Float32Array> {
    return this.pipeline.readSlotRanges(slots);
  }

  /** Active block ids of the drawn surface and the triangles of each (waits for the GPU). */
  readBlockTriangles(): Promise<{ ids: Uint32Array; triangles: Uint32Array }> {
    return this.pipeline.readBlockTriangles();
  }

  destroy(): void {
    this.#stopWork('Isosurface: destroyed');
    this.snapshot?.destroy();
    this.snapshot = null;
  }

  /** Everything but the drawn copy goes; requests waiting are rejected with `message`. */
  #stopWork(message: string): void {
    if (this.destroyed) return;
    this.destroyed = true;
    const error = new Error(message);
    for (const r of [this.pending, ...this.inFlight.map((a) => a.r)]) for (const w of r?.waiters ?? []) w.reject(error);
    this.pending = undefined;
    this.inFlight.length = 0;
    this.stats.destroy();
    this.pipeline.destroy();
    this.statsListeners.clear();
    this.errorListeners.clear();
    this.submitListeners.clear();
  }
}
