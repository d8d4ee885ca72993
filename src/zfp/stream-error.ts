// How far a stream's decoded values are from the values it was made from,
// measured on the GPU while the source is still there (shaders/zfp/
// stream_error.wgsl): the largest absolute error and the root mean square,
// over the voxels of the volume (zfp's padding of partial blocks left out).
// Decoded and source values are float32, as zfpy's decode and numpy's
// astype(np.float32) give them, so the largest error is exactly what
// `np.abs(decoded - source).max()` says.
//
//   const meter = await ZfpErrorMeter.create(device);
//   meter.begin(stream);                    // once per stream
//   meter.encode(encoder, { stream, shard, input, dtype, inputZPlane });   // per shard, after its encode
//   const error = await meter.read();       // { maxAbs, rms, values }
//
// One meter per device (errorMeterFor): its pipelines are compiled once per
// input type, its sums buffer grows to the largest stream measured.
import type { DType } from '../core/dtype.ts';
import { BindGroupCache } from '../gpu/bind-group-cache.ts';
import { perDevice } from '../gpu/per-device.ts';
import { binding, type GpuBufferRef } from '../gpu/buffer-ref.ts';
import { dispatchWorkgroups } from '../gpu/dispatch.ts';
import { bindGroupLayout } from '../gpu/pipeline-cache.ts';
import { UniformSlots } from '../gpu/uniform-slots.ts';
import { DtypePipelines } from './dtype-pipelines.ts';
import { streamBindGroupLayout, type ZfpGpuStream } from './gpu-stream.ts';
import { zfpWgsl } from './wgsl.ts';

const WORKGROUP = 64;

export interface StreamError {
  /** Largest |decoded - source| over the voxels (float32 arithmetic). */
  maxAbs: number;
  /** Root mean square of the same differences. */
  rms: number;
  /** Voxels compared. */
  values: number;
}

export interface ErrorArgs {
  stream: ZfpGpuStream;
  shard: number;
  /** Source values (little endian, x fastest) holding z planes from `inputZPlane` on; what the shard was encoded from. */
  input: GpuBufferRef;
  dtype: DType;
  inputZPlane: number;
}

export class ZfpErrorMeter {
  private readonly groups = new BindGroupCache();
  private readonly uniforms: UniformSlots;
  /** One pipeline per input type (an override constant: no per-value switch). */
  private readonly pipelines: DtypePipelines;
  private readonly maxBuffer: GPUBuffer;
  private sums?: GPUBuffer;
  /** Workgroup sums of the stream being measured: where each shard's start. */
  private sumBase: number[] = [];
  private sumCount = 0;
  private measuring?: ZfpGpuStream;

  private constructor(
    readonly device: GPUDevice,
    private readonly layout: GPUBindGroupLayout,
  ) {
    this.uniforms = new UniformSlots(device, 'ZfpErrorMeter');
    this.pipelines = new DtypePipelines(device, 'ZfpErrorMeter', zfpWgsl.streamError, 'stream_error', [
      streamBindGroupLayout(device),
      layout,
    ]);
    this.maxBuffer = device.createBuffer({
      label: 'ZfpErrorMeter.max',
      size: 4,
      usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST,
    });
  }

  static async create(device: GPUDevice, dtypes: readonly DType[] = []): Promise<ZfpErrorMeter> {
    const layout = bindGroupLayout(device, 'ZfpErrorMeter.layout', [
      { binding: 0, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'read-only-storage' } },
      { binding: 1, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'storage' } },
      { binding: 2, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'storage' } },
      { binding: 3, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'uniform' } },
    ]);
    const meter = new ZfpErrorMeter(device, layout);
    await Promise.all(dtypes.map((t) => meter.prepare(t)));
    return meter;
  }

  /** Compiles the pipeline for source type `dtype` (once). */
  prepare(dtype: DType): Promise<GPUComputePipeline> {
    return this.pipelines.prepare(dtype);
  }

  /** Starts measuring `stream` (its shards are then encoded one by one, in any order). */
  begin(stream: ZfpGpuStream): void {
    this.sumBase = [];
    let n = 0;
    for (const shard of stream.shards) {
      this.sumBase.push(n);
      n += Math.ceil((shard.endBlock - shard.firstBlock) / WORKGROUP);
    }
    this.sumCount = n;
    const bytes = Math.max(4, n * 4);
    if (!this.sums || this.sums.size < bytes) {
      this.sums?.destroy();
      this.sums = this.device.createBuffer({
        label: 'ZfpErrorMeter.sums',
        size: bytes,
        usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST,
      });
    }
    this.device.queue.writeBuffer(this.maxBuffer, 0, new Uint32Array(1));
    this.measuring = stream;
  }

  /** Records the comparison of shard `a.shard` with its source values (pipeline of `a.dtype` prepared first). */
  encode(encoder: GPUCommandEncoder, a: ErrorArgs): void {
    if (a.stream !== this.measuring || !this.sums) throw new Error('ZfpErrorMeter: begin(stream) first');
    const pipeline = this.pipelines.get(a.dtype);
    if (!pipeline) throw new Error(`ZfpErrorMeter: no pipeline for ${a.dtype} yet: await meter.prepare('${a.dtype}') first`);
    const shard = a.stream.shards[a.shard];
    const params = this.uniforms.get(new Uint32Array([a.inputZPlane, this.sumBase[a.shard], 0, 0]));
    const sums = this.sums;
    const group = this.groups
      .ref(a.input)
      .key(sums)
      .key(params.buffer)
      .key(params.offset!)
      .get(() =>
        this.device.createBindGroup({
          label: 'ZfpErrorMeter.bindGroup',
          layout: this.layout,
          entries: [
            { binding: 0, resource: binding(a.input) },
            { binding: 1, resource: { buffer: this.maxBuffer } },
            { binding: 2, resource: { buffer: sums } },
            { binding: 3, resource: params },
          ],
        }),
      );
    const pass = encoder.beginComputePass({ label: 'ZfpErrorMeter.measure' });
    pass.setPipeline(pipeline);
    pass.setBindGroup(0, shard.bindGroup);
    pass.setBindGroup(1, group);
    dispatchWorkgroups(pass, Math.ceil((shard.endBlock - shard.firstBlock) / WORKGROUP));
    pass.end();
  }

  /** The error of the stream begun last, once every shard has been encoded (and submitted). */
  async read(): Promise<StreamError> {
    const stream = this.measuring;
    if (!stream || !this.sums) throw new Error('ZfpErrorMeter: begin(stream) first');
    const sumBytes = this.sumCount * 4;
    const readback = this.device.createBuffer({
      label: 'ZfpErrorMeter.readback',
      size: 4 + sumBytes,
      usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST,
    });
    try {
      const encoder = this.device.createCommandEncoder({ label: 'ZfpErrorMeter.read' });
      encoder.copyBufferToBuffer(this.maxBuffer, 0, readback, 0, 4);
      if (sumBytes > 0) encoder.copyBufferToBuffer(this.sums, 0, readback, 4, sumBytes);
      this.device.queue.submit([encoder.finish()]);
      await readback.mapAsync(GPUMapMode.READ);
      const words = new Float32Array(readback.getMappedRange().slice(0));
      let sum = 0;
      for (let i = 1; i < words.length; i++) sum += words[i];
      const [nx, ny, nz] = stream.info.dims;
      const values = nx * ny * nz;
      return { maxAbs: words[0], rms: Math.sqrt(sum / values), values };
    } finally {
      readback.destroy();
      this.measuring = undefined;
    }
  }

  destroy(): void {
    this.maxBuffer.destroy();
    this.sums?.destroy();
    this.uniforms.destroy();
    this.groups.clear();
  }
}

/** One meter per device (shared by its metered views), created on first use. */
export const errorMeterFor = perDevice((device) => ZfpErrorMeter.create(device));
