// GPU decoder for fixed-rate float32 zfp streams (ZfpGpuStream).
//
//   const decoder = await ZfpDecoder.create(device);           // pipelines, once per device
//   decoder.encodeDecodeBlocks(encoderOrPass, { stream, blockIds, slotIds, count, slots });
//   decoder.encodeBlockRanges(encoderOrPass, { stream, ranges });
//   decoder.encodeDecodeVolume(encoderOrPass, { stream, output });
//
// One invocation decodes one block (workgroups of 64). Every kernel runs once
// per stream shard (bind group 0 = the shard), so streams larger than one
// storage binding work unchanged. The block-list decode is dispatched
// indirectly from a GPU count (no readback): the project's IndirectArgs
// (src/primitives/indirect.ts) turns the count into dispatch arguments in its
// own 16-byte buffer, inside the decode pass.

import { dispatchLinear } from '../gpu/dispatch.ts';
import { createComputePipeline } from '../gpu/wgsl.ts';
import { maxShardBytesFor, streamBindGroupLayout, type ZfpGpuStream } from './gpu-stream.ts';
import {
  BindGroupCache,
  binding,
  inPass,
  refKey,
  refSize,
  UniformSlots,
  type ComputeTarget,
  type GpuBufferRef,
  type GpuCount,
} from './gpu-util.ts';
import { IndirectArgs } from '../primitives/indirect.ts';
import { zfpWgsl } from './wgsl.ts';

export type { ComputeTarget, GpuBufferRef, GpuCount } from './gpu-util.ts';

/**
 * Blocks stored some other way than one contiguous stream (a pool of chunks,
 * src/store): its own bind group 0 per shard and its own decode_blocks
 * pipeline, composed of the same decode core with its own block_start
 * (zfpDecodeCore in wgsl.ts); group 1 must be `decodeBlocksListLayout`'s.
 */
export interface ZfpBlockSource {
  readonly device: GPUDevice;
  readonly isDestroyed: boolean;
  readonly info: { readonly fileName: string };
  readonly shards: readonly { readonly bindGroup: GPUBindGroup }[];
  readonly decodeBlocksPipeline: GPUComputePipeline;
}

/** Group 1 of decode_blocks: block ids, slot ids, dispatch args, slots. */
export function decodeBlocksListLayout(device: GPUDevice): GPUBindGroupLayout {
  const entry = (binding: number, readOnly: boolean): GPUBindGroupLayoutEntry => ({
    binding,
    visibility: GPUShaderStage.COMPUTE,
    buffer: { type: readOnly ? 'read-only-storage' : 'storage' },
  });
  return device.createBindGroupLayout({ label: 'ZfpDecoder.decodeBlocks.layout', entries: [entry(0, true), entry(1, true), entry(2, true), entry(3, false)] });
}

export interface DecodeBlocksArgs {
  stream: ZfpGpuStream | ZfpBlockSource;
  /** u32 block id (raster block order) per list entry. STORAGE usage. */
  blockIds: GpuBufferRef;
  /** u32 destination slot per list entry. STORAGE usage. */
  slotIds: GpuBufferRef;
  /** Number of list entries, a u32 written on the GPU. */
  count: GpuCount;
  /** 64 values per slot (f32, voxel (x, y, z) of the block at x + 4y + 16z). STORAGE usage. */
  slots: GpuBufferRef;
  /** Used when the decoder opens its own pass (target is a command encoder). */
  timestampWrites?: GPUComputePassTimestampWrites;
}

export interface BlockRangesArgs {
  stream: ZfpGpuStream;
  /** 2 f32 (min, max) per block, raster block order; blockCount * 8 bytes. STORAGE usage. */
  ranges: GpuBufferRef;
  timestampWrites?: GPUComputePassTimestampWrites;
}

export interface DecodeVolumeArgs {
  stream: ZfpGpuStream;
  /** f32 voxels x fastest; holds z planes [4 * zBlockBegin, min(4 * zBlockEnd, nz)). STORAGE usage. */
  output: GpuBufferRef;
  /** Block rows (z) to decode; default: all. */
  zBlockBegin?: number;
  zBlockEnd?: number;
  timestampWrites?: GPUComputePassTimestampWrites;
}

export class ZfpDecoder {
  private readonly groups = new BindGroupCache();
  private readonly uniforms: UniformSlots;

  private constructor(
    readonly device: GPUDevice,
    private readonly decodeBlocksPipeline: GPUComputePipeline,
    private readonly decodeVolumePipeline: GPUComputePipeline,
    private readonly rangesPipeline: GPUComputePipeline,
    /** [x, y, z, count] of the indirect block-list dispatch. */
    private readonly args: IndirectArgs,
    private readonly maxWorkgroups: number,
  ) {
    this.uniforms = new UniformSlots(device, 'ZfpDecoder');
  }

  /**
   * @param opts.maxWorkgroupsPerDimension grid limit (default: the device's);
   *   tests lower it so small jobs use 2D grids.
   */
  static async create(device: GPUDevice, opts: { maxWorkgroupsPerDimension?: number } = {}): Promise<ZfpDecoder> {
    const maxWorkgroups = opts.maxWorkgroupsPerDimension ?? device.limits.maxComputeWorkgroupsPerDimension;
    const stream = streamBindGroupLayout(device);
    const storage = (binding: number, readOnly: boolean): GPUBindGroupLayoutEntry => ({
      binding,
      visibility: GPUShaderStage.COMPUTE,
      buffer: { type: readOnly ? 'read-only-storage' : 'storage' },
    });
    const uniform = (binding: number): GPUBindGroupLayoutEntry => ({ binding, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'uniform' } });
    const layout = (label: string, ...entries: GPUBindGroupLayoutEntry[]) => device.createBindGroupLayout({ label, entries });
    const pipelineLayout = (label: string, groups: GPUBindGroupLayout[]) => device.createPipelineLayout({ label, bindGroupLayouts: groups });

    const blocksLayout = decodeBlocksListLayout(device);
    const volumeLayout = layout('ZfpDecoder.decodeVolume.layout', uniform(0), storage(1, false));
    const rangesLayout = layout('ZfpDecoder.blockRanges.layout', storage(0, false));

    const [blocks, volume, ranges, args] = await Promise.all([
      createComputePipeline(device, 'ZfpDecoder.decodeBlocks', zfpWgsl.decodeBlocks, 'decode_blocks', {
        layout: pipelineLayout('ZfpDecoder.decodeBlocks', [stream, blocksLayout]),
      }),
      createComputePipeline(device, 'ZfpDecoder.decodeVolume', zfpWgsl.decodeVolume, 'decode_volume', {
        layout: pipelineLayout('ZfpDecoder.decodeVolume', [stream, volumeLayout]),
      }),
      createComputePipeline(device, 'ZfpDecoder.blockRanges', zfpWgsl.blockRanges, 'block_ranges', {
        layout: pipelineLayout('ZfpDecoder.blockRanges', [stream, rangesLayout]),
      }),
      IndirectArgs.create(device, { itemsPerWorkgroup: 64, maxWorkgroupsPerDimension: maxWorkgroups, label: 'ZfpDecoder.indirectArgs' }),
    ]);
    return new ZfpDecoder(device, blocks, volume, ranges, args, maxWorkgroups);
  }

  private check(stream: ZfpGpuStream | ZfpBlockSource): void {
    if (stream.device !== this.device) throw new Error('ZfpDecoder: the stream belongs to another device');
    if (stream.isDestroyed) throw new Error(`ZfpDecoder: the stream of ${stream.info.fileName} was destroyed`);
  }

  /**
   * Decodes list entries i < count: block blockIds[i] into slot slotIds[i].
   * Dispatched indirectly from the GPU count; allocates nothing once the
   * same buffers have been seen.
   */
  encodeDecodeBlocks(target: ComputeTarget, a: DecodeBlocksArgs): void {
    this.check(a.stream);
    const { device } = this;
    const listGroup = this.groups.get(`blocks|${refKey(a.blockIds)}|${refKey(a.slotIds)}|${refKey(a.slots)}`, () =>
      device.createBindGroup({
        label: 'ZfpDecoder.decodeBlocks.bindGroup',
        layout: this.decodeBlocksPipeline.getBindGroupLayout(1),
        entries: [
          { binding: 0, resource: binding(a.blockIds) },
          { binding: 1, resource: binding(a.slotIds) },
          { binding: 2, resource: { buffer: this.args.buffer } },
          { binding: 3, resource: binding(a.slots) },
        ],
      }),
    );
    inPass(
      target,
      'ZfpDecoder.decodeBlocks',
      (pass) => {
        this.args.encode(pass, { count: a.count });
        pass.setPipeline('decodeBlocksPipeline' in a.stream ? a.stream.decodeBlocksPipeline : this.decodeBlocksPipeline);
        pass.setBindGroup(1, listGroup);
        for (const shard of a.stream.shards) {
          pass.setBindGroup(0, shard.bindGroup);
          pass.dispatchWorkgroupsIndirect(this.args.buffer, 0);
        }
      },
      a.timestampWrites,
    );
  }

  /** Bytes of the ranges buffer for `stream`: 2 f32 per block. */
  static rangesBytes(stream: ZfpGpuStream): number {
    return stream.info.blockCount * 8;
  }

  /** Records the per-block [min, max] over voxels inside the volume (raster block order). */
  encodeBlockRanges(target: ComputeTarget, a: BlockRangesArgs): void {
    this.check(a.stream);
    const need = ZfpDecoder.rangesBytes(a.stream);
    if (refSize(a.ranges) < need) throw new Error(`ZfpDecoder: the ranges buffer has ${refSize(a.ranges)} bytes, ${need} are needed`);
    const group = this.groups.get(`ranges|${refKey(a.ranges)}`, () =>
      this.device.createBindGroup({
        label: 'ZfpDecoder.blockRanges.bindGroup',
        layout: this.rangesPipeline.getBindGroupLayout(1),
        entries: [{ binding: 0, resource: binding(a.ranges) }],
      }),
    );
    inPass(
      target,
      'ZfpDecoder.blockRanges',
      (pass) => {
        pass.setPipeline(this.rangesPipeline);
        pass.setBindGroup(1, group);
        for (const shard of a.stream.shards) {
          pass.setBindGroup(0, shard.bindGroup);
          dispatchLinear(pass, Math.ceil((shard.endBlock - shard.firstBlock) / 64), this.maxWorkgroups);
        }
      },
      a.timestampWrites,
    );
  }

  /** Bytes of z block rows [zBlockBegin, zBlockEnd) decoded as float32. */
  static volumeBytes(stream: ZfpGpuStream, zBlockBegin = 0, zBlockEnd = stream.info.blockGrid[2]): number {
    const [nx, ny, nz] = stream.info.dims;
    return nx * ny * (Math.min(4 * zBlockEnd, nz) - 4 * zBlockBegin) * 4;
  }

  /** Records the decode of z block rows [zBlockBegin, zBlockEnd) into a float32 volume (x fastest). */
  encodeDecodeVolume(target: ComputeTarget, a: DecodeVolumeArgs): void {
    this.check(a.stream);
    const { info } = a.stream;
    const [bx, by, bz] = info.blockGrid;
    const z0 = a.zBlockBegin ?? 0;
    const z1 = a.zBlockEnd ?? bz;
    if (!(Number.isInteger(z0) && Number.isInteger(z1) && z0 >= 0 && z0 < z1 && z1 <= bz)) {
      throw new Error(`ZfpDecoder: block rows [${z0}, ${z1}) are not inside [0, ${bz})`);
    }
    const need = ZfpDecoder.volumeBytes(a.stream, z0, z1);
    if (refSize(a.output) < need) throw new Error(`ZfpDecoder: the output has ${refSize(a.output)} bytes, ${need} are needed`);
    const first = z0 * bx * by;
    const end = z1 * bx * by;
    const work: { shard: number; group: GPUBindGroup; count: number }[] = [];
    a.stream.shards.forEach((shard, s) => {
      const lo = Math.max(first, shard.firstBlock);
      const hi = Math.min(end, shard.endBlock);
      if (lo >= hi) return;
      const params = this.uniforms.get(`volume|${lo}|${hi}|${4 * z0}`, new Uint32Array([lo, hi, 4 * z0, 0]));
      const group = this.groups.get(`volume|${refKey(a.output)}|${lo}|${hi}|${4 * z0}`, () =>
        this.device.createBindGroup({
          label: 'ZfpDecoder.decodeVolume.bindGroup',
          layout: this.decodeVolumePipeline.getBindGroupLayout(1),
          entries: [
            { binding: 0, resource: params },
            { binding: 1, resource: binding(a.output) },
          ],
        }),
      );
      work.push({ shard: s, group, count: hi - lo });
    });
    inPass(
      target,
      'ZfpDecoder.decodeVolume',
      (pass) => {
        pass.setPipeline(this.decodeVolumePipeline);
        for (const w of work) {
          pass.setBindGroup(0, a.stream.shards[w.shard].bindGroup);
          pass.setBindGroup(1, w.group);
          dispatchLinear(pass, Math.ceil(w.count / 64), this.maxWorkgroups);
        }
      },
      a.timestampWrites,
    );
  }

  /** Block-row slabs [z0, z1) whose float32 output fits one storage binding of `maxBytes`. */
  static volumeSlabs(stream: ZfpGpuStream, maxBytes = maxShardBytesFor(stream.device)): [number, number][] {
    const [nx, ny] = stream.info.dims;
    const bz = stream.info.blockGrid[2];
    const rowBytes = nx * ny * 4 * 4;
    const rows = Math.floor(maxBytes / rowBytes);
    if (rows < 1) throw new Error(`${stream.info.fileName}: one row of blocks (${rowBytes} bytes as float32) does not fit one storage binding of ${maxBytes} bytes`);
    const slabs: [number, number][] = [];
    for (let z = 0; z < bz; z += rows) slabs.push([z, Math.min(bz, z + rows)]);
    return slabs;
  }

  /** Decodes the whole volume into a new GPU buffer (STORAGE | COPY_SRC; the caller owns it). Must fit one binding. */
  decodeVolume(stream: ZfpGpuStream): GPUBuffer {
    this.check(stream);
    const size = ZfpDecoder.volumeBytes(stream);
    const max = maxShardBytesFor(this.device);
    if (size > max) throw new Error(`${stream.info.fileName}: the decoded volume (${size} bytes) is larger than one storage binding (${max}); decode it in slabs (encodeDecodeVolume)`);
    const output = this.device.createBuffer({ label: 'ZfpDecoder.volume', size: Math.max(4, size), usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC });
    const encoder = this.device.createCommandEncoder({ label: 'ZfpDecoder.decodeVolume' });
    this.encodeDecodeVolume(encoder, { stream, output });
    this.device.queue.submit([encoder.finish()]);
    return output;
  }

  /** Computes the block ranges into a new GPU buffer (STORAGE | COPY_SRC; the caller owns it). */
  computeBlockRanges(stream: ZfpGpuStream): GPUBuffer {
    this.check(stream);
    const ranges = this.device.createBuffer({
      label: 'ZfpDecoder.ranges',
      size: Math.max(8, ZfpDecoder.rangesBytes(stream)),
      usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC,
    });
    const encoder = this.device.createCommandEncoder({ label: 'ZfpDecoder.blockRanges' });
    this.encodeBlockRanges(encoder, { stream, ranges });
    this.device.queue.submit([encoder.finish()]);
    return ranges;
  }

  /**
   * Decodes the whole volume to the CPU, slab by slab (any size that fits in
   * CPU memory). `sink` receives each slab (float32, x fastest, z planes from
   * `zPlane`); without a sink the volume is returned in one Float32Array.
   * For the CLI and tests, not for interactive paths.
   */
  async readVolume(stream: ZfpGpuStream, opts: { maxSlabBytes?: number; sink?: (zPlane: number, slab: Float32Array) => void } = {}): Promise<Float32Array | undefined> {
    this.check(stream);
    const { device } = this;
    const slabs = ZfpDecoder.volumeSlabs(stream, opts.maxSlabBytes);
    const largest = Math.max(...slabs.map(([z0, z1]) => ZfpDecoder.volumeBytes(stream, z0, z1)));
    const [nx, ny, nz] = stream.info.dims;
    const whole = opts.sink ? undefined : new Float32Array(nx * ny * nz);
    const output = device.createBuffer({ label: 'ZfpDecoder.readVolume.slab', size: largest, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC });
    const staging = device.createBuffer({ label: 'ZfpDecoder.readVolume.staging', size: largest, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
    try {
      for (const [z0, z1] of slabs) {
        const bytes = ZfpDecoder.volumeBytes(stream, z0, z1);
        const encoder = device.createCommandEncoder({ label: 'ZfpDecoder.readVolume' });
        this.encodeDecodeVolume(encoder, { stream, output, zBlockBegin: z0, zBlockEnd: z1 });
        encoder.copyBufferToBuffer(output, 0, staging, 0, bytes);
        device.queue.submit([encoder.finish()]);
        await staging.mapAsync(GPUMapMode.READ, 0, bytes);
        const slab = new Float32Array(staging.getMappedRange(0, bytes));
        if (whole) whole.set(slab, 4 * z0 * nx * ny);
        else opts.sink!(4 * z0, slab);
        staging.unmap();
      }
    } finally {
      output.destroy();
      staging.destroy();
    }
    return whole;
  }

  destroy(): void {
    this.args.destroy();
    this.uniforms.destroy();
    this.groups.clear();
  }
}
