// Statistics of a computation, read back off the critical path: the counters
// and the stage timestamps are copied into a MAP_READ staging buffer (from a
// small ring) at the end of the computation's own submission, and mapped
// after the caller's code has run (a microtask later), so nothing between a
// new isovalue and the draw call waits for them.
//
// Stage times come from timestamp queries written by empty compute passes
// between the stages ("markers"); stage k lasts from marker k to marker k+1.
// Without `timestamp-query` the whole computation is timed by wall clock from
// submit to the staging buffer becoming readable (an upper bound), and the
// source says so.
import type { PassTiming, TimingSource } from '../gpu/timing.ts';
import { COUNTERS_BYTES } from './layout.ts';

/** The timed stages, in order. */
export const STAGES = ['active blocks', 'cache update', 'decompress', 'classify', 'counts and plan', 'cell list', 'vertices'] as const;
const MARKERS = STAGES.length + 1;

export interface RawStats {
  counters: Uint32Array;
  stages: PassTiming[];
  gpuMs: number;
  source: TimingSource;
}

export class StatsReadback {
  readonly source: TimingSource;
  private readonly querySet?: GPUQuerySet;
  private readonly resolveBuffer?: GPUBuffer;
  private readonly free: GPUBuffer[] = [];
  private readonly all: GPUBuffer[] = [];
  private readonly stagingBytes: number;
  private destroyed = false;

  constructor(
    private readonly device: GPUDevice,
    timing: boolean,
  ) {
    this.source = timing && device.features.has('timestamp-query') ? 'timestamp-query' : 'queue-wall-time';
    if (this.source === 'timestamp-query') {
      this.querySet = device.createQuerySet({ label: 'Isosurface.stageTimes', type: 'timestamp', count: MARKERS });
      this.resolveBuffer = device.createBuffer({
        label: 'Isosurface.stageTimes.resolve',
        size: MARKERS * 8,
        usage: GPUBufferUsage.QUERY_RESOLVE | GPUBufferUsage.COPY_SRC,
      });
    }
    this.stagingBytes = COUNTERS_BYTES + MARKERS * 8;
    for (let i = 0; i < 3; i++) this.free.push(this.createStaging());
  }

  private createStaging(): GPUBuffer {
    const b = this.device.createBuffer({
      label: `Isosurface.stats${this.all.length}`,
      size: this.stagingBytes,
      usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST,
    });
    this.all.push(b);
    return b;
  }

  /** Records marker `index` (0 = start, k + 1 = end of stage k). */
  mark(encoder: GPUCommandEncoder, index: number): void {
    if (!this.querySet) return;
    encoder
      .beginComputePass({
        label: `Isosurface.marker${index}`,
        timestampWrites: { querySet: this.querySet, beginningOfPassWriteIndex: index },
      })
      .end();
  }

  /** Records the copies of counters and timestamps; returns the staging buffer to read after submit. */
  encodeCopy(encoder: GPUCommandEncoder, counters: GPUBuffer): GPUBuffer {
    // One per submission in flight: the ring grows to the number of reads outstanding.
    const staging = this.free.pop() ?? this.createStaging();
    encoder.copyBufferToBuffer(counters, 0, staging, 0, COUNTERS_BYTES);
    if (this.querySet && this.resolveBuffer) {
      encoder.resolveQuerySet(this.querySet, 0, MARKERS, this.resolveBuffer, 0);
      encoder.copyBufferToBuffer(this.resolveBuffer, 0, staging, COUNTERS_BYTES, MARKERS * 8);
    }
    return staging;
  }

  /** Returns a staging buffer that was not submitted. */
  release(staging: GPUBuffer): void {
    this.free.push(staging);
  }

  /** Maps `staging` once the GPU is done (requested a microtask after the call). */
  async read(staging: GPUBuffer, submittedAt: number): Promise<RawStats> {
    // Let the caller finish what it is doing (e.g. record its draw) first.
    await null;
    if (this.destroyed) throw new Error('Isosurface: destroyed');
    try {
      await staging.mapAsync(GPUMapMode.READ);
    } catch (e) {
      this.free.push(staging);
      throw e;
    }
    const readableAt = performance.now();
    const bytes = staging.getMappedRange();
    const counters = new Uint32Array(bytes.slice(0, COUNTERS_BYTES));
    const ticks = this.querySet ? new BigInt64Array(bytes.slice(COUNTERS_BYTES, COUNTERS_BYTES + MARKERS * 8)) : undefined;
    staging.unmap();
    this.free.push(staging);
    if (!ticks) {
      const ms = readableAt - submittedAt;
      return { counters, stages: [{ label: 'computation', ms }], gpuMs: ms, source: this.source };
    }
    const stages = STAGES.map((label, k) => ({ label, ms: Math.max(0, Number(ticks[k + 1] - ticks[k])) / 1e6 }));
    return { counters, stages, gpuMs: stages.reduce((s, p) => s + p.ms, 0), source: this.source };
  }

  destroy(): void {
    this.destroyed = true;
    this.querySet?.destroy();
    this.resolveBuffer?.destroy();
    for (const b of this.all) b.destroy();
    this.all.length = 0;
    this.free.length = 0;
  }
}
