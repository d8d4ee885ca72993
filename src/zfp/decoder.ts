// GPU decoder for fixed-rate float32 zfp streams (ZfpGpuStream).
//
//   const decoder = await ZfpDecoder.create(device);           // pipelines, once per device
//   decoder.encodeDecodeBlocks(encoderOrPass, { stream, blockIds, slotIds, count, slots });
//   decoder.encodeBlockRanges(encoderOrPass, { stream, ranges });
//   decoder.encodeDecodeVolume(encoderOrPass, { stream, output });
//
// One invocation decodes one block. The block-list and whole-volume decodes
// have two kernel families each, chosen per adapter like the primitives'
// (choosePath): the emulator path (decode_blocks.wgsl, decode_volume.wgsl:
// each lane stores its own block) and the GPU path (decode_blocks_tiled.wgsl,
// decode_volume_tiled.wgsl via volume-decode.ts: blocks staged in workgroup
// memory and stored by the workgroup, coalesced). Every kernel runs once
// per stream shard (bind group 0 = the shard), so streams larger than one
// storage binding work unchanged. The block-list decode is dispatched
// indirectly from a GPU count (no readback): the project's IndirectArgs
// (src/primitives/indirect.ts) turns the count into dispatch arguments in its
// own 16-byte buffer, inside the decode pass.

import { baseDevice } from '../gpu/memory-meter.ts';
import { BindGroupCache } from '../gpu/bind-group-cache.ts';
import { binding, inPass, refSize, type ComputeTarget, type GpuBufferRef, type GpuCount } from '../gpu/buffer-ref.ts';
import { dispatchWorkgroups } from '../gpu/dispatch.ts';
import { bindGroupLayout, createComputePipeline } from '../gpu/pipeline-cache.ts';
import { UniformSlots } from '../gpu/uniform-slots.ts';
import { choosePath, type PrimitivePath } from '../primitives/dispatch-records.ts';
import { IndirectArgs } from '../primitives/indirect.ts';
import { poolBindGroupLayout, type ChunkedVolume } from './chunked-volume.ts';
import { maxShardBytesFor, streamBindGroupLayout, type BlockSource, type ZfpGpuStream } from './gpu-stream.ts';
import { volumeBytes, VolumeDecodeKernel, volumeSlabs, type DecodeVolumeArgs } from './volume-decode.ts';
import { zfpWgsl } from './wgsl.ts';

export type { DecodeVolumeArgs } from './volume-decode.ts';

export interface DecodeBlocksArgs {
  /** A whole stream, or chunks in a pool (ChunkedVolume). */
  stream: BlockSource;
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

export interface ChunkBlockRangesArgs {
  pool: ChunkedVolume;
  /** u32 chunk indices; ranges of their blocks are recomputed (empty for chunks not resident). */
  chunkList: GpuBufferRef;
  /** ChunkListParams uniform (pool_ranges.wgsl): count, blocks per chunk. */
  params: GpuBufferRef;
  /** Chunks in the list (known on the CPU: the pool's changed chunks). */
  count: number;
  /** 2 f32 per block of the level, raster block order. */
  ranges: GpuBufferRef;
}

export interface ZfpDecoderOptions {
  /** Grid limit (default: the device's); tests lower it so small jobs use 2D grids. */
  maxWorkgroupsPerDimension?: number;
  /** Kernel family of the block-list and whole-volume decodes: 'auto' (default) picks per adapter (choosePath). */
  path?: PrimitivePath | 'auto';
}

/** Invocations per workgroup of the GPU-path block-list decode (workgroup memory: 65 + 1 words each). */
export const TILED_DECODE_WG = 32;

export class ZfpDecoder {
  private readonly blockGroups = new BindGroupCache();
  private readonly poolRangeGroups = new BindGroupCache();
  private readonly rangeGroups = new BindGroupCache();

  private constructor(
    readonly device: GPUDevice,
    private readonly uniforms: UniformSlots,
    private readonly decodeBlocksPipeline: GPUComputePipeline,
    private readonly volumeKernel: VolumeDecodeKernel,
    private readonly rangesPipeline: GPUComputePipeline,
    private readonly decodePoolBlocksPipeline: GPUComputePipeline,
    private readonly poolRangesPipeline: GPUComputePipeline,
    /** [x, y, z, count] of the indirect block-list dispatch. */
    private readonly args: IndirectArgs,
    private readonly maxWorkgroups: number,
    /** Kernel family of the block-list and whole-volume decodes (choosePath). */
    readonly path: PrimitivePath,
  ) {}

  static async create(device: GPUDevice, opts: ZfpDecoderOptions = {}): Promise<ZfpDecoder> {
    const maxWorkgroups = opts.maxWorkgroupsPerDimension ?? device.limits.maxComputeWorkgroupsPerDimension;
    const path = choosePath(device, opts);
    const gpuPath = path === 'gpu';
    const listWg = gpuPath ? TILED_DECODE_WG : 64;
    const wgConst = { name: 'decode_blocks_tiled constants', code: `const WG: u32 = ${listWg}u;\n` };
    const blocksParts = gpuPath ? [wgConst, ...zfpWgsl.decodeBlocksTiled] : zfpWgsl.decodeBlocks;
    const poolBlocksParts = gpuPath ? [wgConst, ...zfpWgsl.decodePoolBlocksTiled] : zfpWgsl.decodePoolBlocks;
    const stream = streamBindGroupLayout(device);
    const storage = (binding: number, readOnly: boolean): GPUBindGroupLayoutEntry => ({
      binding,
      visibility: GPUShaderStage.COMPUTE,
      buffer: { type: readOnly ? 'read-only-storage' : 'storage' },
    });
    const uniform = (binding: number): GPUBindGroupLayoutEntry => ({
      binding,
      visibility: GPUShaderStage.COMPUTE,
      buffer: { type: 'uniform' },
    });
    const layout = (label: string, ...entries: GPUBindGroupLayoutEntry[]) => bindGroupLayout(device, label, entries);

    const blocksLayout = layout('ZfpDecoder.decodeBlocks.layout', storage(0, true), storage(1, true), storage(2, true), storage(3, false));
    const rangesLayout = layout('ZfpDecoder.blockRanges.layout', storage(0, false));
    const pool = poolBindGroupLayout(device);
    const poolRangesLayout = layout('ZfpDecoder.chunkBlockRanges.layout', storage(0, false), storage(1, true), uniform(2));

    const uniforms = new UniformSlots(device, 'ZfpDecoder');
    const [blocks, volume, ranges, poolBlocks, poolRanges, args] = await Promise.all([
      createComputePipeline(device, 'ZfpDecoder.decodeBlocks', blocksParts, 'decode_blocks', {
        layout: [stream, blocksLayout],
      }),
      VolumeDecodeKernel.create(device, path, stream, uniforms, maxWorkgroups),
      createComputePipeline(device, 'ZfpDecoder.blockRanges', zfpWgsl.blockRanges, 'block_ranges', {
        layout: [stream, rangesLayout],
      }),
      createComputePipeline(device, 'ZfpDecoder.decodePoolBlocks', poolBlocksParts, 'decode_blocks', {
        layout: [pool, blocksLayout],
      }),
      createComputePipeline(device, 'ZfpDecoder.chunkBlockRanges', zfpWgsl.poolRanges, 'chunk_block_ranges', {
        layout: [pool, poolRangesLayout],
      }),
      IndirectArgs.create(device, {
        itemsPerWorkgroup: listWg,
        maxWorkgroupsPerDimension: maxWorkgroups,
        label: 'ZfpDecoder.indirectArgs',
      }),
    ]);
    return new ZfpDecoder(device, uniforms, blocks, volume, ranges, poolBlocks, poolRanges, args, maxWorkgroups, path);
  }

  private check(stream: BlockSource): void {
    if (baseDevice(stream.device) !== baseDevice(this.device)) throw new Error('ZfpDecoder: the stream belongs to another device');
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
    const listGroup = this.blockGroups
      .ref(a.blockIds)
      .ref(a.slotIds)
      .ref(a.slots)
      .get(() =>
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
        pass.setPipeline(a.stream.addressing === 'pool' ? this.decodePoolBlocksPipeline : this.decodeBlocksPipeline);
        pass.setBindGroup(1, listGroup);
        for (const shard of a.stream.shards) {
          pass.setBindGroup(0, shard.bindGroup);
          pass.dispatchWorkgroupsIndirect(this.args.buffer, 0);
        }
      },
      a.timestampWrites,
    );
  }

  /**
   * Recomputes the block ranges of the chunks in `chunkList` (once per pool
   * shard: each shard's dispatch covers the chunks in its slots; chunks not
   * resident get the empty range).
   */
  encodeChunkBlockRanges(target: ComputeTarget, a: ChunkBlockRangesArgs): void {
    this.check(a.pool);
    if (a.count === 0) return;
    const group = this.poolRangeGroups
      .ref(a.chunkList)
      .ref(a.params)
      .ref(a.ranges)
      .get(() =>
        this.device.createBindGroup({
          label: 'ZfpDecoder.chunkBlockRanges.bindGroup',
          layout: this.poolRangesPipeline.getBindGroupLayout(1),
          entries: [
            { binding: 0, resource: binding(a.ranges) },
            { binding: 1, resource: binding(a.chunkList) },
            { binding: 2, resource: binding(a.params) },
          ],
        }),
      );
    inPass(target, 'ZfpDecoder.chunkBlockRanges', (pass) => {
      pass.setPipeline(this.poolRangesPipeline);
      pass.setBindGroup(1, group);
      for (const shard of a.pool.shards) {
        pass.setBindGroup(0, shard.bindGroup);
        dispatchWorkgroups(pass, Math.ceil((a.count * a.pool.chunkBlocks ** 3) / 64), this.maxWorkgroups);
      }
    });
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
    const group = this.rangeGroups.ref(a.ranges).get(() =>
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
          dispatchWorkgroups(pass, Math.ceil((shard.endBlock - shard.firstBlock) / 64), this.maxWorkgroups);
        }
      },
      a.timestampWrites,
    );
  }

  /** Bytes of z block rows [zBlockBegin, zBlockEnd) decoded as float32. */
  static volumeBytes(stream: ZfpGpuStream, zBlockBegin = 0, zBlockEnd = stream.info.blockGrid[2]): number {
    return volumeBytes(stream, zBlockBegin, zBlockEnd);
  }

  /** Records the decode of z block rows [zBlockBegin, zBlockEnd) into a float32 volume (x fastest). */
  encodeDecodeVolume(target: ComputeTarget, a: DecodeVolumeArgs): void {
    this.check(a.stream);
    this.volumeKernel.encode(target, a);
  }

  /** Block-row slabs [z0, z1) whose float32 output fits one storage binding of `maxBytes`. */
  static volumeSlabs(stream: ZfpGpuStream, maxBytes = maxShardBytesFor(stream.device)): [number, number][] {
    return volumeSlabs(stream, maxBytes);
  }

  /** Decodes the whole volume into a new GPU buffer (STORAGE | COPY_SRC; the caller owns it). Must fit one binding. */
  decodeVolume(stream: ZfpGpuStream): GPUBuffer {
    this.check(stream);
    const size = ZfpDecoder.volumeBytes(stream);
    const max = maxShardBytesFor(this.device);
    if (size > max)
      throw new Error(
        `${stream.info.fileName}: the decoded volume (${size} bytes) is larger than one storage binding (${max}); decode it in slabs (encodeDecodeVolume)`,
      );
    const output = this.device.createBuffer({
      label: 'ZfpDecoder.volume',
      size: Math.max(4, size),
      usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC,
    });
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
  async readVolume(
    stream: ZfpGpuStream,
    opts: { maxSlabBytes?: number; sink?: (zPlane: number, slab: Float32Array) => void } = {},
  ): Promise<Float32Array | undefined> {
    this.check(stream);
    const { device } = this;
    const slabs = ZfpDecoder.volumeSlabs(stream, opts.maxSlabBytes);
    const largest = Math.max(...slabs.map(([z0, z1]) => ZfpDecoder.volumeBytes(stream, z0, z1)));
    const [nx, ny, nz] = stream.info.dims;
    const whole = opts.sink ? undefined : new Float32Array(nx * ny * nz);
    const output = device.createBuffer({
      label: 'ZfpDecoder.readVolume.slab',
      size: largest,
      usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC,
    });
    const staging = device.createBuffer({
      label: 'ZfpDecoder.readVolume.staging',
      size: largest,
      usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST,
    });
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
    for (const g of [this.blockGroups, this.poolRangeGroups, this.rangeGroups]) g.clear();
    this.volumeKernel.destroy();
  }
}
