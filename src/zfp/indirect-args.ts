// Indirect dispatch arguments from a GPU count, for kernels of 64 invocations
// per workgroup on a 2D grid: [x, y, 1, count] in a 16-byte buffer (INDIRECT |
// STORAGE, so kernels can also read the count at word 3). Runs inside a
// compute pass, and the caller's count buffer needs only STORAGE usage.
// (src/primitives/ has the project-wide dispatch records; this stays small
// and local so the zfp decoder can be recorded into the caller's pass.)

import { createComputePipeline } from '../gpu/wgsl.ts';
import { BindGroupCache, objectId, UniformSlots, type GpuCount } from './gpu-util.ts';
import { zfpWgsl } from './wgsl.ts';

export class IndirectArgs {
  /** [x, y, 1, count]. */
  readonly buffer: GPUBuffer;
  private readonly groups = new BindGroupCache();
  private readonly uniforms: UniformSlots;

  private constructor(readonly device: GPUDevice, private readonly pipeline: GPUComputePipeline, label: string) {
    this.buffer = device.createBuffer({ label: `${label}.args`, size: 16, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.INDIRECT | GPUBufferUsage.COPY_SRC });
    this.uniforms = new UniformSlots(device, label);
  }

  /** `maxWorkgroupsPerDimension` below the device's makes small counts use 2D grids (tests). */
  static async create(device: GPUDevice, label = 'IndirectArgs', maxWorkgroupsPerDimension = device.limits.maxComputeWorkgroupsPerDimension): Promise<IndirectArgs> {
    const layout = device.createBindGroupLayout({
      label: `${label}.layout`,
      entries: [
        { binding: 0, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'read-only-storage' } },
        { binding: 1, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'uniform' } },
        { binding: 2, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'storage' } },
      ],
    });
    const pipeline = await createComputePipeline(device, label, zfpWgsl.indirectArgs, 'indirect_args', {
      layout: device.createPipelineLayout({ label, bindGroupLayouts: [layout] }),
      constants: { MAX_WG: maxWorkgroupsPerDimension },
    });
    return new IndirectArgs(device, pipeline, label);
  }

  /** Records the args computation for `count` (one workgroup) into `pass`. */
  encode(pass: GPUComputePassEncoder, count: GpuCount): void {
    const alignment = this.device.limits.minStorageBufferOffsetAlignment;
    if (count.offset % 4 !== 0) throw new Error(`IndirectArgs: count offset ${count.offset} is not a multiple of 4`);
    const base = Math.floor(count.offset / alignment) * alignment;
    const word = (count.offset - base) / 4;
    const group = this.groups.get(`${objectId(count.buffer)}@${count.offset}`, () =>
      this.device.createBindGroup({
        label: 'IndirectArgs.bindGroup',
        layout: this.pipeline.getBindGroupLayout(0),
        entries: [
          { binding: 0, resource: { buffer: count.buffer, offset: base, size: Math.min(count.buffer.size - base, alignment) } },
          { binding: 1, resource: this.uniforms.get(`word${word}`, new Uint32Array([word, 0, 0, 0])) },
          { binding: 2, resource: { buffer: this.buffer } },
        ],
      }),
    );
    pass.setPipeline(this.pipeline);
    pass.setBindGroup(0, group);
    pass.dispatchWorkgroups(1);
  }

  destroy(): void {
    this.buffer.destroy();
    this.uniforms.destroy();
    this.groups.clear();
  }
}
