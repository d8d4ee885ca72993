// One texel of a depth texture, read on the GPU into a buffer (picking):
// WebGPU copies depth textures only whole, so a one-thread kernel loads the
// texel instead. Made once per device; a probe allocates its small uniform
// and bind group (picks are rare, not per frame).
import depthProbeWgsl from '../../shaders/render/depth_probe.wgsl?raw';
import { createShaderModule } from '../gpu/wgsl.ts';

export class DepthProbe {
  private constructor(
    private readonly device: GPUDevice,
    private readonly pipeline: GPUComputePipeline,
  ) {}

  static async create(device: GPUDevice): Promise<DepthProbe> {
    const module = await createShaderModule(device, 'DepthProbe.shader', [
      { name: 'shaders/render/depth_probe.wgsl', code: depthProbeWgsl },
    ]);
    const pipeline = await device.createComputePipelineAsync({
      label: 'DepthProbe',
      layout: 'auto',
      compute: { module, entryPoint: 'read_depth' },
    });
    return new DepthProbe(device, pipeline);
  }

  /** Writes the depth at (x, y) of `depth` into f32 `slot` of `out` (STORAGE usage), in encoder order; destroy what it returns once submitted. */
  encode(encoder: GPUCommandEncoder, depth: GPUTextureView, x: number, y: number, out: GPUBuffer, slot: number): GPUBuffer {
    const uniform = this.device.createBuffer({
      label: 'DepthProbe.uniform',
      size: 16,
      usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
    });
    this.device.queue.writeBuffer(uniform, 0, Uint32Array.of(x, y, slot, 0));
    const group = this.device.createBindGroup({
      label: 'DepthProbe.group',
      layout: this.pipeline.getBindGroupLayout(0),
      entries: [
        { binding: 0, resource: depth },
        { binding: 1, resource: { buffer: out } },
        { binding: 2, resource: { buffer: uniform } },
      ],
    });
    const pass = encoder.beginComputePass({ label: 'DepthProbe' });
    pass.setPipeline(this.pipeline);
    pass.setBindGroup(0, group);
    pass.dispatchWorkgroups(1);
    pass.end();
    return uniform;
  }
}
