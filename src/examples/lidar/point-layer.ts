// Draws a point cloud as billboarded splats (shaders/points/splat.wgsl). The
// cloud arrives in chunks while it is decoded; each chunk is written into
// GPU batches of up to BATCH_POINTS points, so the view fills in as the file
// loads and no single buffer exceeds the device's binding limit.
import splatWgsl from '../../../shaders/points/splat.wgsl?raw';
import { createShaderModule } from '../../gpu/wgsl.ts';
import { DEPTH_FORMAT, frameSnippet, type RenderLayer, type Viewer } from '../../render/viewer.ts';

export type ColorMode = 'rgb' | 'intensity' | 'elevation' | 'classification';
export type PointShape = 'round' | 'square';

export interface PointStyle {
  colorMode: ColorMode;
  shape: PointShape;
  /** Splat diameter in device pixels. */
  sizePx: number;
  /** Intensity mapped to black..white. */
  intensityRange: [number, number];
  /** Elevation (z relative to the centre) mapped over the colour ramp. */
  zRange: [number, number];
  /** Bit c set: class c (0..31) is hidden. */
  hiddenClasses: number;
}

const COLOR_MODES: Record<ColorMode, number> = { rgb: 0, intensity: 1, elevation: 2, classification: 3 };

/** Points per GPU batch: 48 MiB of positions, 32 MiB of attributes. */
export const BATCH_POINTS = 1 << 22;

interface Batch {
  positions: GPUBuffer;
  attributes: GPUBuffer;
  bindGroup: GPUBindGroup;
  capacity: number;
  filled: number;
}

/** Packs RGB (shifted to 8 bits), classification and intensity into two words per point. */
export function packAttributes(
  count: number,
  rgb: Uint16Array | undefined,
  rgbShift: number,
  intensity: Uint16Array | undefined,
  classification: Uint8Array | undefined,
  out = new Uint32Array(count * 2),
): Uint32Array {
  for (let i = 0; i < count; i++) {
    let w0 = 0;
    if (rgb) {
      const r = Math.min(255, rgb[3 * i] >> rgbShift);
      const g = Math.min(255, rgb[3 * i + 1] >> rgbShift);
      const b = Math.min(255, rgb[3 * i + 2] >> rgbShift);
      w0 = r | (g << 8) | (b << 16);
    }
    const cls = classification ? classification[i] : 1;
    out[2 * i] = (w0 | (cls << 24)) >>> 0;
    out[2 * i + 1] = intensity ? intensity[i] : 0;
  }
  return out;
}

export class PointLayer implements RenderLayer {
  private readonly uniforms: GPUBuffer;
  private batches: Batch[] = [];
  private total = 0;
  private uploaded = 0;
  visible = true;
  style: PointStyle = {
    colorMode: 'rgb',
    shape: 'round',
    sizePx: 3,
    intensityRange: [0, 65535],
    zRange: [-1, 1],
    hiddenClasses: 0,
  };

  private constructor(
    private readonly viewer: Viewer,
    private readonly pipeline: GPURenderPipeline,
    private readonly layout: GPUBindGroupLayout,
  ) {
    this.uniforms = viewer.device.createBuffer({
      label: 'PointLayer.style',
      size: 48,
      usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
    });
    this.writeStyle();
  }

  static async create(viewer: Viewer): Promise<PointLayer> {
    const { device } = viewer;
    const module = await createShaderModule(device, 'PointLayer.shader', [
      frameSnippet,
      { name: 'shaders/points/splat.wgsl', code: splatWgsl },
    ]);
    const layout = device.createBindGroupLayout({
      label: 'PointLayer.layout',
      entries: [
        { binding: 0, visibility: GPUShaderStage.VERTEX | GPUShaderStage.FRAGMENT, buffer: { type: 'uniform' } },
        { binding: 1, visibility: GPUShaderStage.VERTEX, buffer: { type: 'read-only-storage' } },
        { binding: 2, visibility: GPUShaderStage.VERTEX, buffer: { type: 'read-only-storage' } },
      ],
    });
    const pipeline = await device.createRenderPipelineAsync({
      label: 'PointLayer.pipeline',
      layout: device.createPipelineLayout({ bindGroupLayouts: [viewer.frameBindGroupLayout, layout] }),
      vertex: { module, entryPoint: 'vs' },
      fragment: { module, entryPoint: 'fs', targets: [{ format: viewer.format }] },
      primitive: { topology: 'triangle-list' },
      depthStencil: { format: DEPTH_FORMAT, depthWriteEnabled: true, depthCompare: 'less' },
    });
    return new PointLayer(viewer, pipeline, layout);
  }

  /** Points uploaded so far. */
  get pointCount(): number {
    return this.uploaded;
  }

  /** GPU memory held by the point buffers. */
  get gpuBytes(): number {
    return this.batches.reduce((s, b) => s + b.positions.size + b.attributes.size, 0);
  }

  /** Frees the current cloud and prepares for one of `total` points. */
  reset(total: number): void {
    for (const b of this.batches) {
      b.positions.destroy();
      b.attributes.destroy();
    }
    this.batches = [];
    this.total = total;
    this.uploaded = 0;
    this.viewer.requestFrame();
  }

  /**
   * Appends `count` points (positions x,y,z and two attribute words each).
   * `redraw: false` defers the frame (loaders redraw a few times a second,
   * not after every chunk, so slow GPUs are not swamped while loading).
   */
  append(positions: Float32Array, attributes: Uint32Array, count: number, redraw = true): void {
    const { device } = this.viewer;
    let done = 0;
    while (done < count) {
      let batch = this.batches[this.batches.length - 1];
      if (!batch || batch.filled === batch.capacity) {
        const capacity = Math.min(BATCH_POINTS, Math.max(1, this.total - this.uploaded), 1 << 30);
        const n = this.batches.length;
        const pos = device.createBuffer({
          label: `PointLayer.positions[${n}]`,
          size: capacity * 12,
          usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST,
        });
        const attr = device.createBuffer({
          label: `PointLayer.attributes[${n}]`,
          size: capacity * 8,
          usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST,
        });
        batch = {
          positions: pos,
          attributes: attr,
          capacity,
          filled: 0,
          bindGroup: device.createBindGroup({
            label: `PointLayer.bindGroup[${n}]`,
            layout: this.layout,
            entries: [
              { binding: 0, resource: { buffer: this.uniforms } },
              { binding: 1, resource: { buffer: pos } },
              { binding: 2, resource: { buffer: attr } },
            ],
          }),
        };
        this.batches.push(batch);
      }
      const n = Math.min(count - done, batch.capacity - batch.filled);
      // Chunks never live in shared memory; the DOM typings just cannot know that.
      device.queue.writeBuffer(batch.positions, batch.filled * 12, positions as Float32Array<ArrayBuffer>, done * 3, n * 3);
      device.queue.writeBuffer(batch.attributes, batch.filled * 8, attributes as Uint32Array<ArrayBuffer>, done * 2, n * 2);
      batch.filled += n;
      this.uploaded += n;
      done += n;
    }
    if (redraw) this.viewer.requestFrame();
  }

  setStyle(change: Partial<PointStyle>): void {
    this.style = { ...this.style, ...change };
    this.writeStyle();
    this.viewer.requestFrame();
  }

  private writeStyle(): void {
    const s = this.style;
    const data = new ArrayBuffer(48);
    const u = new Uint32Array(data);
    const f = new Float32Array(data);
    u[0] = COLOR_MODES[s.colorMode];
    u[1] = s.shape === 'round' ? 1 : 0;
    f[2] = s.sizePx;
    f[3] = 1 / 255;
    f[4] = s.intensityRange[0];
    f[5] = s.intensityRange[1];
    f[6] = s.zRange[0];
    f[7] = s.zRange[1];
    u[8] = s.hiddenClasses >>> 0;
    this.viewer.device.queue.writeBuffer(this.uniforms, 0, data);
  }

  draw(pass: GPURenderPassEncoder): void {
    if (!this.visible) return;
    pass.setPipeline(this.pipeline);
    for (const b of this.batches) {
      if (b.filled === 0) continue;
      pass.setBindGroup(1, b.bindGroup);
      pass.draw(6, b.filled);
    }
  }

  destroy(): void {
    this.reset(0);
    this.uniforms.destroy();
  }
}
