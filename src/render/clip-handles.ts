// The clip's handles (shaders/render/clip_handles.wgsl): discs at the clip
// box's faces and at the plane's centre and rotation knob, lines for the
// plane's outline and the knob's stick; sizes in pixels, so they stay
// grabbable when zoomed out. An overlay (Viewer.addOverlay): drawn over the
// finished scene, see-through surfaces included. The owner lists the items
// (clear, disc, line, upload) when the clip or the hovered handle changes;
// a frame only records one draw.
import handlesWgsl from '../../shaders/render/clip_handles.wgsl?raw';
import { createShaderModule } from '../gpu/wgsl.ts';
import { frameSnippet, type RenderLayer, type Viewer } from './viewer.ts';

/** The items one layer holds (the shader's uniform array). */
export const MAX_HANDLE_ITEMS = 16;
const ITEM_FLOATS = 16;

type Rgb = readonly [number, number, number] | readonly number[];

export class ClipHandleLayer implements RenderLayer {
  readonly #uniforms: GPUBuffer;
  readonly #bindGroup: GPUBindGroup;
  readonly #data = new Float32Array(MAX_HANDLE_ITEMS * ITEM_FLOATS);
  #count = 0;

  private constructor(
    private readonly device: GPUDevice,
    private readonly pipeline: GPURenderPipeline,
    layout: GPUBindGroupLayout,
  ) {
    this.#uniforms = device.createBuffer({
      label: 'ClipHandleLayer.uniforms',
      size: this.#data.byteLength,
      usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
    });
    this.#bindGroup = device.createBindGroup({
      label: 'ClipHandleLayer.bindGroup',
      layout,
      entries: [{ binding: 0, resource: { buffer: this.#uniforms } }],
    });
  }

  static async create(viewer: Viewer): Promise<ClipHandleLayer> {
    const { device } = viewer;
    const module = await createShaderModule(device, 'ClipHandleLayer.shader', [
      frameSnippet,
      { name: 'shaders/render/clip_handles.wgsl', code: handlesWgsl },
    ]);
    const layout = device.createBindGroupLayout({
      label: 'ClipHandleLayer.layout',
      entries: [{ binding: 0, visibility: GPUShaderStage.VERTEX | GPUShaderStage.FRAGMENT, buffer: { type: 'uniform' } }],
    });
    const pipeline = await device.createRenderPipelineAsync({
      label: 'ClipHandleLayer.pipeline',
      layout: device.createPipelineLayout({ bindGroupLayouts: [viewer.frameBindGroupLayout, layout] }),
      vertex: { module, entryPoint: 'vs' },
      fragment: { module, entryPoint: 'fs', targets: [{ format: viewer.format }] },
      primitive: { topology: 'triangle-list' },
    });
    return new ClipHandleLayer(device, pipeline, layout);
  }

  /** Items listed so far. */
  get count(): number {
    return this.#count;
  }

  clear(): void {
    this.#count = 0;
  }

  /** A disc of `radius` pixels at world point p. */
  disc(p: ArrayLike<number>, radius: number, color: Rgb): void {
    this.#item(p, p, color, radius, 0);
  }

  /** A line from a to b (world), `width` pixels wide. */
  line(a: ArrayLike<number>, b: ArrayLike<number>, width: number, color: Rgb): void {
    this.#item(a, b, color, width / 2, 1);
  }

  /** Sends the items listed to the GPU (drawn from the next frame). */
  upload(): void {
    if (this.#count > 0) this.device.queue.writeBuffer(this.#uniforms, 0, this.#data, 0, this.#count * ITEM_FLOATS);
  }

  draw(pass: GPURenderPassEncoder): void {
    if (this.#count === 0) return;
    pass.setPipeline(this.pipeline);
    pass.setBindGroup(1, this.#bindGroup);
    pass.draw(6 * this.#count);
  }

  destroy(): void {
    this.#uniforms.destroy();
  }

  #item(a: ArrayLike<number>, b: ArrayLike<number>, color: Rgb, size: number, shape: number): void {
    if (this.#count >= MAX_HANDLE_ITEMS) return;
    const d = this.#data;
    const o = this.#count++ * ITEM_FLOATS;
    d[o] = a[0];
    d[o + 1] = a[1];
    d[o + 2] = a[2];
    d[o + 3] = 1;
    d[o + 4] = b[0];
    d[o + 5] = b[1];
    d[o + 6] = b[2];
    d[o + 7] = 1;
    d[o + 8] = color[0];
    d[o + 9] = color[1];
    d[o + 10] = color[2];
    d[o + 11] = 1;
    d[o + 12] = size;
    d[o + 13] = shape;
    d[o + 14] = 0;
    d[o + 15] = 0;
  }
}
