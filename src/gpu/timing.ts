// Per-pass GPU durations from timestamp queries where the device has
// `timestamp-query`; otherwise the wall time from submit to
// onSubmittedWorkDone for the whole submission. Every result says which.
//
// Usage, once per submission:
//   const frame = timer.begin();                 // reuses pooled buffers
//   pass = encoder.beginComputePass({ timestampWrites: frame.pass('scan') });
//   ...
//   frame.resolve(encoder); queue.submit([...]); const t = await frame.read();

export type TimingSource = 'timestamp-query' | 'queue-wall-time';

export interface PassTiming {
  label: string;
  ms: number;
}

export interface SubmissionTiming {
  source: TimingSource;
  /** Per pass with timestamp queries; one entry 'submission' otherwise. */
  passes: PassTiming[];
  /** Sum over passes (timestamps) or the wall time (fallback). */
  totalMs: number;
}

interface QuerySlot {
  querySet: GPUQuerySet;
  resolveBuffer: GPUBuffer;
  readBuffer: GPUBuffer;
  busy: boolean;
}

export class GpuTimer {
  readonly source: TimingSource;
  private readonly slots: QuerySlot[] = [];

  /**
   * @param maxPasses most timed passes in one submission (two queries each).
   */
  constructor(
    private readonly device: GPUDevice,
    readonly maxPasses = 32,
    enabled = device.features.has('timestamp-query'),
  ) {
    this.source = enabled ? 'timestamp-query' : 'queue-wall-time';
  }

  /** Starts recording the timing of one submission. */
  begin(): TimedSubmission {
    if (this.source === 'queue-wall-time') return new TimedSubmission(this.device, this.source, undefined, this.maxPasses);
    let slot = this.slots.find((s) => !s.busy);
    if (!slot) {
      const count = this.maxPasses * 2;
      slot = {
        querySet: this.device.createQuerySet({ label: 'GpuTimer.querySet', type: 'timestamp', count }),
        resolveBuffer: this.device.createBuffer({
          label: 'GpuTimer.resolve',
          size: count * 8,
          usage: GPUBufferUsage.QUERY_RESOLVE | GPUBufferUsage.COPY_SRC,
        }),
        readBuffer: this.device.createBuffer({
          label: 'GpuTimer.read',
          size: count * 8,
          usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST,
        }),
        busy: false,
      };
      this.slots.push(slot);
    }
    slot.busy = true;
    return new TimedSubmission(this.device, this.source, slot, this.maxPasses);
  }

  destroy(): void {
    for (const s of this.slots) {
      s.querySet.destroy();
      s.resolveBuffer.destroy();
      s.readBuffer.destroy();
    }
    this.slots.length = 0;
  }
}

export class TimedSubmission {
  private readonly labels: string[] = [];
  private submittedAt = 0;

  constructor(
    private readonly device: GPUDevice,
    readonly source: TimingSource,
    private readonly slot: QuerySlot | undefined,
    private readonly maxPasses: number,
  ) {}

  /** timestampWrites for a pass (undefined without timestamp queries). */
  pass(label: string): GPUComputePassTimestampWrites | undefined {
    if (!this.slot) return undefined;
    if (this.labels.length >= this.maxPasses) throw new Error(`GpuTimer: more than ${this.maxPasses} timed passes in one submission`);
    const i = this.labels.length;
    this.labels.push(label);
    return { querySet: this.slot.querySet, beginningOfPassWriteIndex: 2 * i, endOfPassWriteIndex: 2 * i + 1 };
  }

  /** Render passes take the same shape of timestampWrites. */
  renderPass(label: string): GPURenderPassTimestampWrites | undefined {
    return this.pass(label);
  }

  /** Records the query resolve; call after the last timed pass. */
  resolve(encoder: GPUCommandEncoder): void {
    if (!this.slot || this.labels.length === 0) return;
    const n = this.labels.length * 2;
    encoder.resolveQuerySet(this.slot.querySet, 0, n, this.slot.resolveBuffer, 0);
    encoder.copyBufferToBuffer(this.slot.resolveBuffer, 0, this.slot.readBuffer, 0, n * 8);
  }

  /** Call right after queue.submit (used by the wall-time fallback). */
  submitted(): void {
    this.submittedAt = performance.now();
  }

  /** Reads the durations once the GPU is done; does not block other work. */
  async read(): Promise<SubmissionTiming> {
    if (!this.slot) {
      const start = this.submittedAt || performance.now();
      await this.device.queue.onSubmittedWorkDone();
      const ms = performance.now() - start;
      return { source: this.source, passes: [{ label: 'submission', ms }], totalMs: ms };
    }
    const slot = this.slot;
    try {
      if (this.labels.length === 0) return { source: this.source, passes: [], totalMs: 0 };
      await slot.readBuffer.mapAsync(GPUMapMode.READ, 0, this.labels.length * 16);
      const ticks = new BigInt64Array(slot.readBuffer.getMappedRange(0, this.labels.length * 16).slice(0));
      slot.readBuffer.unmap();
      const passes = this.labels.map((label, i) => {
        const ns = Number(ticks[2 * i + 1] - ticks[2 * i]);
        return { label, ms: Math.max(0, ns) / 1e6 };
      });
      return { source: this.source, passes, totalMs: passes.reduce((s, p) => s + p.ms, 0) };
    } finally {
      slot.busy = false;
    }
  }
}
