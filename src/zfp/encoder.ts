// GPU encoder: volumes of uint8/int8/uint16/int16/float32/float64 (converted
// to float32 as numpy's astype does) to zfp fixed-rate streams, bit-exact with
// zfp 1.0.1 (`zfpy.compress_numpy(a.astype(np.float32), rate=R)`), with or
// without zfp's header.
//
//   const enc = await ZfpEncoder.create(device);
//   const stream = await enc.compressToStream(bytes, 'uint8', [X, Y, Z], 4, { header: true }); // stays on the GPU
//   const file = await stream.readBytes();                                                   // zfp's file bytes
//
// One invocation encodes one block; the output stream is cut into shards of
// whole z rows of blocks (each shard one storage binding), and the input is
// uploaded one slab of z planes per shard, so neither needs to fit a binding.

import type { DType } from '../core/dtype.ts';
import { DTYPE_BYTES } from '../core/dtype.ts';
import { formatDims, type Dims } from '../core/naming.ts';
import { BindGroupCache } from '../gpu/bind-group-cache.ts';
import { binding, refSize, type GpuBufferRef } from '../gpu/buffer-ref.ts';
import { dispatchWorkgroups } from '../gpu/dispatch.ts';
import { perDevice } from '../gpu/per-device.ts';
import { bindGroupLayout } from '../gpu/pipeline-cache.ts';
import { UniformSlots } from '../gpu/uniform-slots.ts';
import { DTYPE_CODE, DtypePipelines } from './dtype-pipelines.ts';
import { planZfpStream, ZfpFormatError, type ZfpStreamInfo } from './format.ts';
import { maxShardBytesFor, planShards, ZfpGpuStream } from './gpu-stream.ts';
import { writeZfpHeader } from './header.ts';
import type { StreamError, ZfpErrorMeter } from './stream-error.ts';
import { zfpWgsl } from './wgsl.ts';

export interface EncodeArgs {
  /** Input values (little endian, x fastest) holding z planes from `inputZPlane` on. STORAGE usage. */
  input: GpuBufferRef;
  dtype: DType;
  /** First z plane in `input`; must be <= 4 * (first z block row of the shard). */
  inputZPlane: number;
  /** Target stream from createStream(); `shard` is the one written. */
  stream: ZfpGpuStream;
  shard: number;
  timestampWrites?: GPUComputePassTimestampWrites;
}

/** One chunk encoded into its slot of a larger buffer (encodeSlot). */
export interface SlotEncodeArgs {
  /** The chunk's values (little endian, x fastest), at least dims' count of `dtype`. STORAGE usage. */
  input: GpuBufferRef;
  dtype: DType;
  /** The chunk's stream: planZfpStream(name, [C, C, C], rate, true). */
  info: ZfpStreamInfo;
  /** Where the stream goes: STORAGE | COPY_DST, the slot at `byteOffset` (a multiple of 8), info.paddedBytes long. */
  target: GPUBuffer;
  byteOffset: number;
}

interface DispatchRecord {
  input: GpuBufferRef;
  output: GPUBufferBinding;
  dims: readonly number[];
  dtype: DType;
  blockGrid: readonly number[];
  bitsPerBlock: number;
  firstBlock: number;
  endBlock: number;
  bitBase: number;
  inputZPlane: number;
  header: { bits: number; bytes: Uint8Array } | null;
  headerWord: number;
  timestampWrites?: GPUComputePassTimestampWrites;
}

export interface CompressOptions {
  /** Write zfp's header (default true): 96 bits, 148 when bitsPerBlock > 2048. */
  header?: boolean;
  /** Name used in messages and in the stream info. */
  fileName?: string;
  /** Cap on the shard (and input slab) size; default: one storage binding. */
  maxShardBytes?: number;
}

export class ZfpEncoder {
  private readonly groups = new BindGroupCache();
  private readonly uniforms: UniformSlots;
  /** One pipeline per input type (an override constant: no per-value switch). */
  private readonly pipelines: DtypePipelines;

  private constructor(
    readonly device: GPUDevice,
    private readonly groupLayout: GPUBindGroupLayout,
  ) {
    this.uniforms = new UniformSlots(device, 'ZfpEncoder');
    this.pipelines = new DtypePipelines(device, 'ZfpEncoder.encode', zfpWgsl.encode, 'encode_blocks', [groupLayout]);
  }

  /** Compiles the pipelines for `dtypes` now (others are compiled on first use by compress*(), or by prepare()). */
  static async create(device: GPUDevice, dtypes: readonly DType[] = ['float32']): Promise<ZfpEncoder> {
    const group = bindGroupLayout(device, 'ZfpEncoder.layout', [
      { binding: 0, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'read-only-storage' } },
      { binding: 1, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'storage' } },
      { binding: 2, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'uniform' } },
    ]);
    const encoder = new ZfpEncoder(device, group);
    await Promise.all(dtypes.map((t) => encoder.prepare(t)));
    return encoder;
  }

  /** Compiles the pipeline for input type `dtype` (once). */
  prepare(dtype: DType): Promise<GPUComputePipeline> {
    return this.pipelines.prepare(dtype);
  }

  /**
   * Plans and allocates (zeroed) the output stream for `info`: shards of whole
   * z rows of blocks whose input slab (of `dtype`) and output both fit `maxShardBytes`.
   */
  createStream(info: ZfpStreamInfo, dtype: DType, maxShardBytes = maxShardBytesFor(this.device)): ZfpGpuStream {
    const [bx, by] = info.blockGrid;
    const [nx, ny] = info.dims;
    const rowInputBytes = nx * ny * 4 * DTYPE_BYTES[dtype];
    const rowsPerSlab = Math.floor(maxShardBytes / rowInputBytes);
    if (rowsPerSlab < 1)
      throw new ZfpFormatError(
        `${info.fileName}: 4 z planes of ${formatDims(info.dims)} ${dtype} (${rowInputBytes} bytes) do not fit one storage binding of ${maxShardBytes} bytes`,
      );
    const plans = planShards(info, maxShardBytes, bx * by, rowsPerSlab * bx * by);
    return ZfpGpuStream.create(this.device, info, plans, 'ZfpEncoder.stream');
  }

  /** z planes [first, end) of the input that shard `s` of `stream` needs. */
  static shardPlanes(stream: ZfpGpuStream, s: number): [number, number] {
    const [bx, by] = stream.info.blockGrid;
    const shard = stream.shards[s];
    const z0 = Math.floor(shard.firstBlock / (bx * by));
    const z1 = Math.ceil(shard.endBlock / (bx * by));
    return [4 * z0, Math.min(4 * z1, stream.info.dims[2])];
  }

  /**
   * Records the encoding of shard `a.shard` (clears it, then one dispatch).
   * Needs a command encoder (the clear is not a pass command), and the
   * pipeline of `a.dtype` (create() or prepare()).
   */
  encode(encoder: GPUCommandEncoder, a: EncodeArgs): void {
    const { stream } = a;
    const pipeline = this.pipelines.get(a.dtype);
    if (!pipeline) throw new Error(`ZfpEncoder: no pipeline for ${a.dtype} yet: await encoder.prepare('${a.dtype}') first`);
    if (stream.isDestroyed) throw new Error('ZfpEncoder: the target stream was destroyed');
    const info = stream.info;
    const shard = stream.shards[a.shard];
    if (!shard) throw new Error(`ZfpEncoder: the stream has no shard ${a.shard}`);
    const [p0, p1] = ZfpEncoder.shardPlanes(stream, a.shard);
    if (a.inputZPlane > p0) throw new Error(`ZfpEncoder: shard ${a.shard} needs z planes from ${p0}, the input starts at ${a.inputZPlane}`);
    const [nx, ny] = info.dims;
    const needBytes = nx * ny * (p1 - a.inputZPlane) * DTYPE_BYTES[a.dtype];
    if (refSize(a.input) < needBytes)
      throw new Error(`ZfpEncoder: the input has ${refSize(a.input)} bytes, shard ${a.shard} needs ${needBytes}`);

    let header: { bits: number; bytes: Uint8Array } | null = null;
    if (info.hasHeader && shard.firstBlock === 0) header = writeZfpHeader(info.dims, info.bitsPerBlock);
    encoder.clearBuffer(shard.buffer);
    this.#dispatch(encoder, pipeline, {
      input: a.input,
      output: { buffer: shard.buffer },
      dims: info.dims,
      dtype: a.dtype,
      blockGrid: info.blockGrid,
      bitsPerBlock: info.bitsPerBlock,
      firstBlock: shard.firstBlock,
      endBlock: shard.endBlock,
      bitBase: shard.bitBase,
      inputZPlane: a.inputZPlane,
      header,
      headerWord: 0,
      timestampWrites: a.timestampWrites,
    });
  }

  /**
   * Records the encoding of one C^3 chunk into its place in a larger buffer
   * (a pool slot of src/zfp/chunked-volume.ts): the slot's bytes are
   * cleared, then the chunk is written there as the stream zfpy writes for
   * it (header included), nothing else in `a.target` touched. The target is
   * bound from the 256-byte boundary below the slot, so the bit offsets
   * stay small whatever the slot's place. Needs the pipeline of `a.dtype`.
   */
  encodeSlot(encoder: GPUCommandEncoder, a: SlotEncodeArgs): void {
    const pipeline = this.pipelines.get(a.dtype);
    if (!pipeline) throw new Error(`ZfpEncoder: no pipeline for ${a.dtype} yet: await encoder.prepare('${a.dtype}') first`);
    const { info, byteOffset } = a;
    if (byteOffset % 8 !== 0 || info.paddedBytes % 8 !== 0 || byteOffset + info.paddedBytes > a.target.size)
      throw new Error(`ZfpEncoder: a slot of ${info.paddedBytes} bytes at ${byteOffset} does not fit its buffer of ${a.target.size}`);
    const blocks = info.blockGrid[0] * info.blockGrid[1] * info.blockGrid[2];
    const values = info.dims[0] * info.dims[1] * info.dims[2];
    if (refSize(a.input) < values * DTYPE_BYTES[a.dtype])
      throw new Error(`ZfpEncoder: the input has ${refSize(a.input)} bytes, a ${formatDims(info.dims)} ${a.dtype} chunk needs more`);
    const align = this.device.limits.minStorageBufferOffsetAlignment;
    const bindOffset = Math.floor(byteOffset / align) * align;
    const lead = byteOffset - bindOffset;
    const header = info.hasHeader ? writeZfpHeader(info.dims, info.bitsPerBlock) : null;
    encoder.clearBuffer(a.target, byteOffset, info.paddedBytes);
    this.#dispatch(encoder, pipeline, {
      input: a.input,
      output: { buffer: a.target, offset: bindOffset, size: lead + info.paddedBytes },
      dims: info.dims,
      dtype: a.dtype,
      blockGrid: info.blockGrid,
      bitsPerBlock: info.bitsPerBlock,
      firstBlock: 0,
      endBlock: blocks,
      bitBase: lead * 8 + info.payloadBitOffset,
      inputZPlane: 0,
      header,
      headerWord: lead / 4,
    });
  }

  #dispatch(encoder: GPUCommandEncoder, pipeline: GPUComputePipeline, d: DispatchRecord): void {
    const header = new Uint32Array(8);
    let headerWords = 0;
    if (d.header) {
      headerWords = Math.ceil(d.header.bits / 32);
      new Uint8Array(header.buffer).set(d.header.bytes);
    }
    const record = new Uint32Array([
      ...d.dims,
      DTYPE_CODE[d.dtype],
      ...d.blockGrid,
      d.bitsPerBlock,
      d.firstBlock,
      d.endBlock,
      d.bitBase,
      d.inputZPlane,
      headerWords,
      d.headerWord,
      0,
      0,
      ...header,
    ]);
    const params = this.uniforms.get(record);
    const out = d.output;
    const group = this.groups
      .ref(d.input)
      .key(out.buffer)
      .key(out.offset ?? 0)
      .key(out.size ?? -1)
      .key(params.buffer)
      .key(params.offset!)
      .get(() =>
        this.device.createBindGroup({
          label: 'ZfpEncoder.bindGroup',
          layout: this.groupLayout,
          entries: [
            { binding: 0, resource: binding(d.input) },
            { binding: 1, resource: out },
            { binding: 2, resource: params },
          ],
        }),
      );
    const desc: GPUComputePassDescriptor = { label: 'ZfpEncoder.encode' };
    if (d.timestampWrites) desc.timestampWrites = d.timestampWrites;
    const pass = encoder.beginComputePass(desc);
    pass.setPipeline(pipeline);
    pass.setBindGroup(0, group);
    dispatchWorkgroups(pass, Math.ceil((d.endBlock - d.firstBlock) / 64));
    pass.end();
  }

  /**
   * Compresses a volume held on the CPU (`bytes`: little endian, x fastest)
   * into a new GPU stream (the caller owns it; decode it directly, or read
   * it back with readBytes()). Uploads one input slab per shard.
   */
  async compressToStream(bytes: Uint8Array, dtype: DType, dims: Dims, rate: number, opts: CompressOptions = {}): Promise<ZfpGpuStream> {
    return (await this.#compress(bytes, dtype, dims, rate, opts)).stream;
  }

  /**
   * compressToStream, and the stream's error against `bytes` measured by
   * `meter` while each input slab is still on the GPU (one more pass per
   * shard, no readback but the error's).
   */
  async compressMeasured(
    bytes: Uint8Array,
    dtype: DType,
    dims: Dims,
    rate: number,
    meter: ZfpErrorMeter,
    opts: CompressOptions = {},
  ): Promise<{ stream: ZfpGpuStream; error: StreamError }> {
    const { stream, error } = await this.#compress(bytes, dtype, dims, rate, opts, meter);
    return { stream, error: error! };
  }

  async #compress(
    bytes: Uint8Array,
    dtype: DType,
    dims: Dims,
    rate: number,
    opts: CompressOptions,
    meter?: ZfpErrorMeter,
  ): Promise<{ stream: ZfpGpuStream; error?: StreamError }> {
    const fileName = opts.fileName ?? `volume_${formatDims(dims)}_${dtype}.raw`;
    const info = planZfpStream(fileName, dims, rate, opts.header ?? true);
    const expect = dims[0] * dims[1] * dims[2] * DTYPE_BYTES[dtype];
    if (bytes.byteLength !== expect) {
      throw new ZfpFormatError(`${fileName}: ${formatDims(dims)} ${dtype} is ${expect} bytes, got ${bytes.byteLength}`);
    }
    const { device } = this;
    await this.prepare(dtype);
    if (meter) await meter.prepare(dtype);
    const stream = this.createStream(info, dtype, opts.maxShardBytes ?? maxShardBytesFor(device));
    const planeBytes = dims[0] * dims[1] * DTYPE_BYTES[dtype];
    let input: GPUBuffer | undefined;
    let error: StreamError | undefined;
    try {
      meter?.begin(stream);
      const slabs = stream.shards.map((_, s) => ZfpEncoder.shardPlanes(stream, s));
      const largest = Math.max(...slabs.map(([z0, z1]) => (z1 - z0) * planeBytes));
      input = device.createBuffer({
        label: 'ZfpEncoder.input',
        size: Math.ceil(largest / 4) * 4,
        usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST,
      });
      for (let s = 0; s < stream.shards.length; s++) {
        const [z0, z1] = slabs[s];
        const slab = bytes.subarray(z0 * planeBytes, z1 * planeBytes);
        const whole = slab.byteLength & ~3;
        if (whole > 0) device.queue.writeBuffer(input, 0, slab.buffer, slab.byteOffset, whole);
        if (whole < slab.byteLength) {
          const tail = new Uint8Array(4);
          tail.set(slab.subarray(whole));
          device.queue.writeBuffer(input, whole, tail);
        }
        const encoder = device.createCommandEncoder({ label: 'ZfpEncoder.compress' });
        this.encode(encoder, { input, dtype, inputZPlane: z0, stream, shard: s });
        meter?.encode(encoder, { input, dtype, inputZPlane: z0, stream, shard: s });
        device.queue.submit([encoder.finish()]);
      }
      if (meter) error = await meter.read();
      else await device.queue.onSubmittedWorkDone();
    } catch (e) {
      stream.destroy();
      throw e;
    } finally {
      input?.destroy();
    }
    return { stream, error };
  }

  /** Compresses to zfp's file bytes (see compressToStream). */
  async compress(
    bytes: Uint8Array,
    dtype: DType,
    dims: Dims,
    rate: number,
    opts: CompressOptions = {},
  ): Promise<{ bytes: Uint8Array; info: ZfpStreamInfo }> {
    const stream = await this.compressToStream(bytes, dtype, dims, rate, opts);
    try {
      return { bytes: await stream.readBytes(), info: stream.info };
    } finally {
      stream.destroy();
    }
  }

  destroy(): void {
    this.uniforms.destroy();
    this.groups.clear();
  }
}

/** One encoder per device (shared by its metered views), created on first use. */
export const encoderFor = perDevice((device) => ZfpEncoder.create(device));
