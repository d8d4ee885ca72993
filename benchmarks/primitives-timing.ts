// GPU time of recorded work for the primitives benchmark: two empty compute
// passes bracket the work, the end of the first and the start of the second
// take timestamps (so multi-pass primitives are timed as a whole); without
// `timestamp-query`, the queue wall time from submit to done.
export type TimingSource = 'timestamp-query' | 'queue-wall-time';

export class BracketTimer {
  readonly source: TimingSource;
  private readonly querySet?: GPUQuerySet;
  private readonly resolve?: GPUBuffer;
  private readonly readback?: GPUBuffer;

  constructor(private readonly device: GPUDevice) {
    this.source = device.features.has('timestamp-query') ? 'timestamp-query' : 'queue-wall-time';
    if (this.source === 'timestamp-query') {
      this.querySet = device.createQuerySet({ label: 'bench.querySet', type: 'timestamp', count: 2 });
      this.resolve = device.createBuffer({
        label: 'bench.resolve',
        size: 16,
        usage: GPUBufferUsage.QUERY_RESOLVE | GPUBufferUsage.COPY_SRC,
      });
      this.readback = device.createBuffer({ label: 'bench.readback', size: 16, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
    }
  }

  /** Milliseconds of GPU time for the work `record` puts in one encoder. */
  async time(record: (encoder: GPUCommandEncoder) => void): Promise<number> {
    const { device } = this;
    const encoder = device.createCommandEncoder({ label: 'bench' });
    if (this.querySet) encoder.beginComputePass({ timestampWrites: { querySet: this.querySet, endOfPassWriteIndex: 0 } }).end();
    record(encoder);
    if (this.querySet) {
      encoder.beginComputePass({ timestampWrites: { querySet: this.querySet, beginningOfPassWriteIndex: 1 } }).end();
      encoder.resolveQuerySet(this.querySet, 0, 2, this.resolve!, 0);
      encoder.copyBufferToBuffer(this.resolve!, 0, this.readback!, 0, 16);
    }
    const t0 = performance.now();
    device.queue.submit([encoder.finish()]);
    await device.queue.onSubmittedWorkDone();
    const wall = performance.now() - t0;
    if (!this.readback) return wall;
    await this.readback.mapAsync(GPUMapMode.READ);
    const t = new BigInt64Array(this.readback.getMappedRange().slice(0));
    this.readback.unmap();
    return Number(t[1] - t[0]) / 1e6;
  }

  destroy(): void {
    this.querySet?.destroy();
    this.resolve?.destroy();
    this.readback?.destroy();
  }
}
