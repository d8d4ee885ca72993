// Caps on a cut-open volume (shaders/render/cap.wgsl): per clip plane, the
// polygon where it cuts the volume's box and the other planes keep it
// (src/core/clip.ts capPolygons), drawn opaque in the volume's colours
// wherever the value there is at least the threshold. The blocks near the
// caps are decoded from the stream by the zfp decoder the cache uses, once
// per clip (a slab per plane: about 2 block layers), into buffers of this
// layer; a new threshold or colour range only rewrites the uniforms.
import capWgsl from '../../shaders/render/cap.wgsl?raw';
import { type Clip, capBlocks, capPolygons } from '../core/clip.ts';
import { createShaderModule } from '../gpu/wgsl.ts';
import { ZfpDecoder } from '../zfp/decoder.ts';
import type { ZfpGpuStream } from '../zfp/gpu-stream.ts';
import type { RenderTarget } from './surface-layer.ts';
import { DEPTH_FORMAT, frameSnippet, type RenderLayer } from './viewer.ts';

const UNIFORM_BYTES = 80;

export class CapLayer implements RenderLayer {
  visible = true;
  /** World size of a voxel and where voxel (0, 0, 0) sits (as the surface layer's). */
  voxelSize: [number, number, number] = [1, 1, 1];
  origin: [number, number, number] = [0, 0, 0];
  /** Drawn where the value is at least this (the outermost surface's isovalue). */
  threshold = 0;
  /** The values the colour map spans. */
  range: [number, number] = [0, 1];

  #stream: ZfpGpuStream | undefined;
  #vertices: GPUBuffer | undefined;
  #vertexCount = 0;
  #blocks: GPUBuffer | undefined;
  #values: GPUBuffer | undefined;
  #listed = 0;
  #bindGroup: GPUBindGroup | undefined;
  readonly #uniforms: GPUBuffer;
  readonly #scratch = new ArrayBuffer(UNIFORM_BYTES);
  readonly #i32 = new Int32Array(this.#scratch);
  readonly #u32 = new Uint32Array(this.#scratch);
  readonly #f32 = new Float32Array(this.#scratch);

  private constructor(
    private readonly device: GPUDevice,
    private readonly pipeline: GPURenderPipeline,
    private readonly decoder: ZfpDecoder,
  ) {
    this.#uniforms = device.createBuffer({
      label: 'CapLayer.uniforms',
      size: UNIFORM_BYTES,
      usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
    });
  }

  static async create(target: RenderTarget): Promise<CapLayer> {
    const { device } = target;
    const module = await createShaderModule(device, 'CapLayer.shader', [frameSnippet, { name: 'shaders/render/cap.wgsl', code: capWgsl }]);
    const layout = device.createBindGroupLayout({
      label: 'CapLayer.layout',
      entries: [
        { binding: 0, visibility: GPUShaderStage.VERTEX | GPUShaderStage.FRAGMENT, buffer: { type: 'uniform' } },
        { binding: 1, visibility: GPUShaderStage.FRAGMENT, buffer: { type: 'read-only-storage' } },
        { binding: 2, visibility: GPUShaderStage.FRAGMENT, buffer: { type: 'read-only-storage' } },
      ],
    });
    const [pipeline, decoder] = await Promise.all([
      device.createRenderPipelineAsync({
        label: 'CapLayer.pipeline',
        layout: device.createPipelineLayout({ label: 'CapLayer', bindGroupLayouts: [target.frameBindGroupLayout, layout] }),
        vertex: {
          module,
          entryPoint: 'vs',
          buffers: [{ arrayStride: 12, attributes: [{ shaderLocation: 0, offset: 0, format: 'float32x3' }] }],
        },
        fragment: { module, entryPoint: 'fs', targets: [{ format: target.format }] },
        primitive: { topology: 'triangle-list', cullMode: 'none' },
        depthStencil: { format: DEPTH_FORMAT, depthWriteEnabled: true, depthCompare: 'less' },
      }),
      ZfpDecoder.create(device),
    ]);
    return new CapLayer(device, pipeline, decoder);
  }

  /** Bytes the caps hold on the GPU (polygons, decoded blocks and their list). */
  get byteSize(): number {
    return (this.#vertices?.size ?? 0) + (this.#blocks?.size ?? 0) + (this.#values?.size ?? 0);
  }

  /** Blocks decoded for the caps now. */
  get blocks(): number {
    return this.#listed;
  }

  /**
   * The caps of `clip` on `stream`'s volume (undefined: none): polygons made
   * and the blocks near them decoded now (on the GPU, in queue order), when
   * they fit `maxBytes`; else none, and why.
   */
  setClip(stream: ZfpGpuStream | undefined, clip: Clip | undefined, maxBytes = Number.POSITIVE_INFINITY): string | null {
    this.#release();
    this.#stream = stream;
    if (!stream || !clip) return null;
    const { dims } = stream.info;
    const caps = capPolygons(clip, dims);
    if (caps.length === 0) return null;
    const triangles: number[] = [];
    for (const cap of caps) {
      for (let i = 1; i + 1 < cap.corners.length; i++) triangles.push(...cap.corners[0], ...cap.corners[i], ...cap.corners[i + 1]);
    }
    const ids = capBlocks(caps, dims);
    const needed = 260 * ids.length + 4 * triangles.length;
    if (needed > maxBytes)
      return `the caps need ${(needed / 2 ** 20).toFixed(1)} MiB for the ${ids.length.toLocaleString('en-US')} blocks along the cut, more than the GPU memory budget leaves (${(Math.max(0, maxBytes) / 2 ** 20).toFixed(1)} MiB)`;
    const { device } = this;
    const make = (label: string, size: number, usage: number) =>
      device.createBuffer({ label: `CapLayer.${label}`, size: Math.max(16, size), usage });
    this.#vertices = make('vertices', 4 * triangles.length, GPUBufferUsage.VERTEX | GPUBufferUsage.COPY_DST);
    device.queue.writeBuffer(this.#vertices, 0, Float32Array.from(triangles));
    this.#vertexCount = triangles.length / 3;
    const storage = GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST | GPUBufferUsage.COPY_SRC;
    this.#blocks = make('blocks', 4 * ids.length, storage);
    device.queue.writeBuffer(this.#blocks, 0, ids as Uint32Array<ArrayBuffer>);
    this.#values = make('values', 256 * ids.length, storage);
    this.#listed = ids.length;
    if (ids.length > 0) {
      // slot k of the decoded values is listed block k
      const slots = make('slots', 4 * ids.length, storage);
      device.queue.writeBuffer(
        slots,
        0,
        Uint32Array.from({ length: ids.length }, (_, k) => k),
      );
      const count = make('count', 16, storage);
      device.queue.writeBuffer(count, 0, Uint32Array.of(ids.length));
      const encoder = device.createCommandEncoder({ label: 'CapLayer.decode' });
      this.decoder.encodeDecodeBlocks(encoder, {
        stream,
        blockIds: this.#blocks,
        slotIds: slots,
        count: { buffer: count, offset: 0 },
        slots: this.#values,
      });
      device.queue.submit([encoder.finish()]);
      slots.destroy();
      count.destroy();
    }
    this.#bindGroup = device.createBindGroup({
      label: 'CapLayer.bindGroup',
      layout: this.pipeline.getBindGroupLayout(1),
      entries: [
        { binding: 0, resource: { buffer: this.#uniforms } },
        { binding: 1, resource: { buffer: this.#blocks } },
        { binding: 2, resource: { buffer: this.#values } },
      ],
    });
    return null;
  }

  draw(pass: GPURenderPassEncoder): void {
    const stream = this.#stream;
    if (!this.visible || !stream || !this.#bindGroup || this.#vertexCount === 0) return;
    const i32 = this.#i32,
      u32 = this.#u32,
      f32 = this.#f32;
    const { dims, blockGrid } = stream.info;
    for (let a = 0; a < 3; a++) {
      i32[a] = dims[a];
      u32[4 + a] = blockGrid[a];
      f32[8 + a] = this.voxelSize[a];
      f32[12 + a] = this.origin[a];
    }
    i32[3] = this.#listed;
    f32[11] = this.threshold;
    f32[16] = this.range[0];
    f32[17] = this.range[1];
    this.device.queue.writeBuffer(this.#uniforms, 0, this.#scratch);
    pass.setPipeline(this.pipeline);
    pass.setBindGroup(1, this.#bindGroup);
    pass.setVertexBuffer(0, this.#vertices!);
    pass.draw(this.#vertexCount);
  }

  #release(): void {
    for (const b of [this.#vertices, this.#blocks, this.#values]) b?.destroy();
    this.#vertices = this.#blocks = this.#values = undefined;
    this.#bindGroup = undefined;
    this.#vertexCount = 0;
    this.#listed = 0;
  }

  destroy(): void {
    this.#release();
    this.#uniforms.destroy();
    this.decoder.destroy();
  }
}
