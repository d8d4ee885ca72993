// The volume's bounding box as lines, so users see the extent of the data
// even where the surface is empty.
import boxWgsl from '../../shaders/render/box.wgsl?raw';
import type { Bounds } from './camera.ts';
import { createShaderModule } from '../gpu/wgsl.ts';
import { DEPTH_FORMAT, frameSnippet, type RenderLayer, type Viewer } from './viewer.ts';

export class BoxLayer implements RenderLayer {
  private readonly uniforms: GPUBuffer;
  private readonly bindGroup: GPUBindGroup;

  private constructor(
    private readonly device: GPUDevice,
    private readonly pipeline: GPURenderPipeline,
    layout: GPUBindGroupLayout,
  ) {
    this.uniforms = device.createBuffer({ label: 'BoxLayer.uniforms', size: 48, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
    this.bindGroup = device.createBindGroup({
      label: 'BoxLayer.bindGroup',
      layout,
      entries: [{ binding: 0, resource: { buffer: this.uniforms } }],
    });
  }

  static async create(viewer: Viewer): Promise<BoxLayer> {
    const { device } = viewer;
    const module = await createShaderModule(device, 'BoxLayer.shader', [frameSnippet, { name: 'shaders/render/box.wgsl', code: boxWgsl }]);
    const layout = device.createBindGroupLayout({
      label: 'BoxLayer.layout',
      entries: [{ binding: 0, visibility: GPUShaderStage.VERTEX | GPUShaderStage.FRAGMENT, buffer: { type: 'uniform' } }],
    });
    const pipeline = await device.createRenderPipelineAsync({
      label: 'BoxLayer.pipeline',
      layout: device.createPipelineLayout({ bindGroupLayouts: [viewer.frameBindGroupLayout, layout] }),
      vertex: { module, entryPoint: 'vs' },
      fragment: { module, entryPoint: 'fs', targets: [{ format: viewer.format }] },
      primitive: { topology: 'line-list' },
      depthStencil: { format: DEPTH_FORMAT, depthWriteEnabled: true, depthCompare: 'less-equal' },
    });
    return new BoxLayer(device, pipeline, layout);
  }

  setBounds(bounds: Bounds, color: [number, number, number, number] = [0.55, 0.6, 0.68, 1]): void {
    this.device.queue.writeBuffer(this.uniforms, 0, new Float32Array([...bounds.min, 1, ...bounds.max, 1, ...color]));
  }

  draw(pass: GPURenderPassEncoder): void {
    pass.setPipeline(this.pipeline);
    pass.setBindGroup(1, this.bindGroup);
    pass.draw(24);
  }

  destroy(): void {
    this.uniforms.destroy();
  }
}
