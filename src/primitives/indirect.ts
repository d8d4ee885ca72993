// dispatchWorkgroupsIndirect arguments from a GPU-side element count, with
// 2D/3D grids past maxComputeWorkgroupsPerDimension; no readback, no host
// loops. The one IndirectArgs of the project (the primitives, the zfp
// decoder's block lists, ...): a one-invocation kernel reads the count from a
// storage binding, so it runs inside the caller's compute pass as well as in
// a pass of its own, and writes [x, y, z, count] into its own 16-byte buffer
// (INDIRECT | STORAGE | COPY_SRC; kernels may read the count at word 3).
// Kernels dispatched with it rebuild the linear workgroup index with
// `grid_workgroup_index` / `grid_invocation_index` of shaders/common/grid.wgsl
// (the grid is its `dispatch_grid`) and skip indices past the count.

import indirectWgsl from '../../shaders/primitives/indirect_args.wgsl?raw';
import { BindGroupCache } from '../gpu/bind-group-cache.ts';
import { isCommandEncoder, type ComputeTarget, type GpuCount } from '../gpu/buffer-ref.ts';
import { gridSnippet } from '../gpu/dispatch.ts';
import { bindGroupLayout, createComputePipeline } from '../gpu/pipeline-cache.ts';
import { toGpuCount, type CountLike } from './count.ts';
import { maxWorkgroupsPerDimension, type PrimitiveOptions } from './dispatch-records.ts';

export interface IndirectArgsOptions extends Pick<PrimitiveOptions, 'maxWorkgroupsPerDimension'> {
  /** Elements one workgroup of the target kernel handles. */
  itemsPerWorkgroup: number;
  label?: string;
}

export interface IndirectArgsEncodeArgs {
  /** Elements; a GpuCount's buffer needs STORAGE usage (any 4-byte offset). */
  count: CountLike;
  /**
   * Also copy (x, y, z) here (12 bytes; the buffer needs COPY_DST, and
   * INDIRECT to be used). Only when recording into a command encoder.
   */
  out?: GpuCount;
}

/** Word index k of a count at byte offset 4k past a 256-aligned base: one uniform slot per k. */
const WORDS_PER_BINDING = 64;
const SLOT_STRIDE = 256;

export class IndirectArgs {
  /** [x, y, z, count] of the last recorded count. */
  readonly buffer: GPUBuffer;
  private readonly wordIndex: GPUBuffer;
  private readonly layout: GPUBindGroupLayout;
  /** setBindGroup's dynamic offset, reused (nothing allocated per encode). */
  private readonly dynamicOffset = new Uint32Array(1);
  private readonly groups = new BindGroupCache();

  private constructor(
    private readonly device: GPUDevice,
    private readonly pipeline: GPUComputePipeline,
    private readonly label: string,
  ) {
    this.layout = pipeline.getBindGroupLayout(0);
    this.buffer = device.createBuffer({
      label: `${label}.args`,
      size: 16,
      usage: GPUBufferUsage.STORAGE | GPUBufferUsage.INDIRECT | GPUBufferUsage.COPY_SRC,
    });
    // The word index of each slot, written once: bound with a dynamic offset.
    this.wordIndex = device.createBuffer({
      label: `${label}.wordIndex`,
      size: WORDS_PER_BINDING * SLOT_STRIDE,
      usage: GPUBufferUsage.UNIFORM,
      mappedAtCreation: true,
    });
    const words = new Uint32Array(this.wordIndex.getMappedRange());
    for (let k = 0; k < WORDS_PER_BINDING; k++) words[(k * SLOT_STRIDE) / 4] = k;
    this.wordIndex.unmap();
  }

  static async create(device: GPUDevice, options: IndirectArgsOptions): Promise<IndirectArgs> {
    const items = options.itemsPerWorkgroup;
    if (!Number.isInteger(items) || items < 1) throw new RangeError('itemsPerWorkgroup must be a positive integer');
    const label = options.label ?? 'IndirectArgs';
    const layout = bindGroupLayout(device, 'IndirectArgs.layout', [
      { binding: 0, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'read-only-storage' } },
      { binding: 1, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'uniform', hasDynamicOffset: true, minBindingSize: 16 } },
      { binding: 2, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'storage' } },
    ]);
    const pipeline = await createComputePipeline(
      device,
      label,
      [gridSnippet, { name: 'shaders/primitives/indirect_args.wgsl', code: indirectWgsl }],
      'indirect_args',
      {
        layout: [layout],
        constants: { ITEMS: items, MAX_WG_PER_DIM: maxWorkgroupsPerDimension(device, options) },
      },
    );
    return new IndirectArgs(device, pipeline, label);
  }

  /** The bind group reading the counts of the 256-byte block at `base` of `buffer`. */
  private bind(buffer: GPUBuffer, base: number): GPUBindGroup {
    return this.groups
      .key(buffer)
      .key(base)
      .get(() =>
        this.device.createBindGroup({
          label: `${this.label}.bindGroup`,
          layout: this.layout,
          entries: [
            { binding: 0, resource: { buffer, offset: base, size: Math.min(buffer.size - base, WORDS_PER_BINDING * 4) } },
            { binding: 1, resource: { buffer: this.wordIndex, size: 16 } },
            { binding: 2, resource: { buffer: this.buffer } },
          ],
        }),
      );
  }

  /**
   * Records the arguments for `count`: into `target` if it is a compute pass
   * (one dispatch; the pipeline and bind group 0 are left changed), else in a
   * pass of its own, then the copy to `out` if given.
   */
  encode(target: ComputeTarget, args: IndirectArgsEncodeArgs): void {
    const count = toGpuCount(this.device, args.count);
    if (count.offset % 4 !== 0) throw new RangeError('count.offset must be a multiple of 4');
    if (args.out && args.out.offset % 4 !== 0) throw new RangeError('out.offset must be a multiple of 4');
    const base = Math.floor(count.offset / (WORDS_PER_BINDING * 4)) * WORDS_PER_BINDING * 4;
    const group = this.bind(count.buffer, base);
    this.dynamicOffset[0] = ((count.offset - base) / 4) * SLOT_STRIDE;
    const isEncoder = isCommandEncoder(target);
    if (!isEncoder && args.out) throw new Error('IndirectArgs: `out` needs a command encoder (it is a buffer copy)');
    const pass = isEncoder ? target.beginComputePass({ label: this.label }) : target;
    pass.setPipeline(this.pipeline);
    pass.setBindGroup(0, group, this.dynamicOffset, 0, 1);
    pass.dispatchWorkgroups(1);
    if (isEncoder) {
      pass.end();
      if (args.out) target.copyBufferToBuffer(this.buffer, 0, args.out.buffer, args.out.offset, 12);
    }
  }

  destroy(): void {
    this.buffer.destroy();
    this.wordIndex.destroy();
    this.groups.clear();
  }
}
