// Ray-marched volume rendering (shaders/volume/raymarch.wgsl) of a scalar
// volume in a 3D texture: 8-bit data as r8unorm, everything else normalised
// to [0, 1] over the data's range as r16float (both filterable, so the GPU
// interpolates trilinearly). A transfer function texture maps the window of
// values to colour and opacity.
import { mat4 } from 'gl-matrix';
import raymarchWgsl from '../../../shaders/volume/raymarch.wgsl?raw';
import { createShaderModule } from '../../gpu/wgsl.ts';
import type { Bounds } from '../../render/camera.ts';
import { DEPTH_FORMAT, frameSnippet, type RenderLayer, type Viewer } from '../../render/viewer.ts';
import type { DepthPrepass } from './depth-prepass.ts';
import { bakeTransferFunction, type TransferFunction } from './transfer-function.ts';

export type Vec3 = [number, number, number];
type Samples = Uint8Array | Int8Array | Uint16Array | Int16Array | Uint32Array | Int32Array | Float32Array | Float64Array;

export interface ScalarVolume {
  /** x, y, z sample counts. */
  dims: Vec3;
  /** World size of a voxel. */
  spacing: Vec3;
  /** [z][y][x][channel] samples. */
  data: Samples;
  channels: number;
}

export interface VolumeSummary {
  /** Data value of normalised 0 and 1. */
  range: [number, number];
  /** 256-bin histogram of normalised values. */
  histogram: Float64Array;
  /** Texture size (smaller than dims when the volume had to be reduced). */
  textureDims: Vec3;
  format: GPUTextureFormat;
  gpuBytes: number;
  /** Suggested window (normalised): the bulk of the background below, the brightest structures at the top. */
  suggestedWindow: [number, number];
}

export type RenderMode = 'composite' | 'mip';

const UNIFORM_BYTES = 64 + 16 + 16 + 32;

// float32 -> float16 bits (round to nearest even), for r16float textures.
const f32 = new Float32Array(1);
const u32 = new Uint32Array(f32.buffer);
export function toHalf(v: number): number {
  f32[0] = v;
  const x = u32[0];
  const sign = (x >>> 16) & 0x8000;
  const exp = (x >>> 23) & 0xff;
  let mant = x & 0x7fffff;
  if (exp === 0xff) return sign | 0x7c00 | (mant ? 0x200 : 0);
  const e = exp - 127 + 15;
  if (e >= 0x1f) return sign | 0x7c00;
  if (e <= 0) {
    if (e < -10) return sign;
    mant |= 0x800000;
    const shift = 14 - e;
    const half = 1 << (shift - 1);
    const rounded = (mant + half - 1 + ((mant >>> shift) & 1)) >>> shift;
    return sign | rounded;
  }
  const rounded = mant + 0xfff + ((mant >>> 13) & 1);
  if (rounded & 0x800000) return e + 1 >= 0x1f ? sign | 0x7c00 : sign | ((e + 1) << 10);
  return sign | (e << 10) | (rounded >>> 13);
}

export class VolumeLayer implements RenderLayer {
  private readonly uniforms: GPUBuffer;
  private readonly tfTexture: GPUTexture;
  private readonly sampler: GPUSampler;
  private texture: GPUTexture | undefined;
  private bindGroup: GPUBindGroup | undefined;
  private box: Bounds = { min: [0, 0, 0], max: [1, 1, 1] };
  private refStep = 1;
  visible = true;
  mode: RenderMode = 'composite';
  /** Samples per voxel along a ray. */
  quality = 1.5;
  opacity = 0.35;
  window: [number, number] = [0, 1];
  private readonly scratch = new ArrayBuffer(UNIFORM_BYTES);
  // Written every frame: views and matrices made once (the render loop allocates nothing).
  private readonly f32 = new Float32Array(this.scratch);
  private readonly u32 = new Uint32Array(this.scratch);
  private readonly viewProj = mat4.create();
  private readonly inverse = mat4.create();
  private readonly size: Vec3 = [0, 0, 0];

  private constructor(
    private readonly viewer: Viewer,
    private readonly prepass: DepthPrepass,
    private readonly pipeline: GPURenderPipeline,
    private readonly layout: GPUBindGroupLayout,
  ) {
    const { device } = viewer;
    this.uniforms = device.createBuffer({
      label: 'VolumeLayer.uniforms',
      size: UNIFORM_BYTES,
      usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
    });
    this.tfTexture = device.createTexture({
      label: 'VolumeLayer.transferFunction',
      size: [256, 1],
      format: 'rgba8unorm',
      usage: GPUTextureUsage.TEXTURE_BINDING | GPUTextureUsage.COPY_DST,
    });
    this.sampler = device.createSampler({ label: 'VolumeLayer.sampler', magFilter: 'linear', minFilter: 'linear' });
    prepass.onResize(() => this.rebind());
    // Uniforms depend on the camera: refresh them at the start of every frame.
    viewer.addBeforeFrame(() => this.writeUniforms());
  }

  static async create(viewer: Viewer, prepass: DepthPrepass): Promise<VolumeLayer> {
    const { device } = viewer;
    const module = await createShaderModule(device, 'VolumeLayer.shader', [
      frameSnippet,
      { name: 'shaders/volume/raymarch.wgsl', code: raymarchWgsl },
    ]);
    const layout = device.createBindGroupLayout({
      label: 'VolumeLayer.layout',
      entries: [
        { binding: 0, visibility: GPUShaderStage.VERTEX | GPUShaderStage.FRAGMENT, buffer: { type: 'uniform' } },
        { binding: 1, visibility: GPUShaderStage.FRAGMENT, texture: { sampleType: 'float', viewDimension: '3d' } },
        { binding: 2, visibility: GPUShaderStage.FRAGMENT, sampler: { type: 'filtering' } },
        { binding: 3, visibility: GPUShaderStage.FRAGMENT, texture: { sampleType: 'float' } },
        { binding: 4, visibility: GPUShaderStage.FRAGMENT, texture: { sampleType: 'depth' } },
      ],
    });
    const pipeline = await device.createRenderPipelineAsync({
      label: 'VolumeLayer.pipeline',
      layout: device.createPipelineLayout({ bindGroupLayouts: [viewer.frameBindGroupLayout, layout] }),
      vertex: { module, entryPoint: 'vs' },
      fragment: {
        module,
        entryPoint: 'fs',
        // Premultiplied colour over what is already drawn.
        targets: [
          {
            format: viewer.format,
            blend: {
              color: { srcFactor: 'one', dstFactor: 'one-minus-src-alpha', operation: 'add' },
              alpha: { srcFactor: 'one', dstFactor: 'one-minus-src-alpha', operation: 'add' },
            },
          },
        ],
      },
      // Back faces: rays start right also with the camera inside the box.
      primitive: { topology: 'triangle-list', cullMode: 'front' },
      // Occlusion by opaque layers is handled in the shader (pre-pass depth).
      depthStencil: { format: DEPTH_FORMAT, depthWriteEnabled: false, depthCompare: 'always' },
    });
    return new VolumeLayer(viewer, prepass, pipeline, layout);
  }

  get bounds(): Bounds {
    return this.box;
  }

  get hasVolume(): boolean {
    return this.texture !== undefined;
  }

  setTransferFunction(tf: TransferFunction): void {
    this.viewer.device.queue.writeTexture({ texture: this.tfTexture }, bakeTransferFunction(tf), { bytesPerRow: 256 * 4 }, [256, 1]);
    this.viewer.requestFrame();
  }

  /** Uploads a volume (replacing the previous one); returns what the panel shows. */
  setVolume(v: ScalarVolume): VolumeSummary {
    const { device } = this.viewer;
    const limit = device.limits.maxTextureDimension3D;
    // Keep every axis within the device's 3D texture limit (nearest sample).
    const stride = v.dims.map((d) => Math.ceil(d / limit)) as Vec3;
    const tdims = v.dims.map((d, a) => Math.ceil(d / stride[a])) as Vec3;
    const eightBit = v.data instanceof Uint8Array && v.channels === 1;
    const format: GPUTextureFormat = eightBit ? 'r8unorm' : 'r16float';

    // Range of the data (over channel means for multi-channel data).
    let lo = Infinity;
    let hi = -Infinity;
    const value = (i: number): number => {
      if (v.channels === 1) return v.data[i];
      let s = 0;
      for (let c = 0; c < v.channels; c++) s += v.data[i * v.channels + c];
      return s / v.channels;
    };
    const n = v.dims[0] * v.dims[1] * v.dims[2];
    if (eightBit) {
      lo = 0;
      hi = 255;
    } else {
      for (let i = 0; i < n; i++) {
        const x = value(i);
        if (x < lo) lo = x;
        if (x > hi) hi = x;
      }
      if (!(hi > lo)) hi = lo + 1;
    }
    const scale = 1 / (hi - lo);
    const histogram = new Float64Array(256);

    this.texture?.destroy();
    this.texture = device.createTexture({
      label: 'VolumeLayer.volume',
      size: tdims,
      dimension: '3d',
      format,
      usage: GPUTextureUsage.TEXTURE_BINDING | GPUTextureUsage.COPY_DST,
    });
    const [tw, th, td] = tdims;
    const [nx, ny] = v.dims;
    const bpp = eightBit ? 1 : 2;
    const slice = eightBit ? new Uint8Array(tw * th) : new Uint16Array(tw * th);
    for (let z = 0; z < td; z++) {
      const sz = z * stride[2];
      for (let y = 0; y < th; y++) {
        const row = (sz * ny + y * stride[1]) * nx;
        for (let x = 0; x < tw; x++) {
          const i = row + x * stride[0];
          if (eightBit) {
            const b = v.data[i];
            slice[y * tw + x] = b;
            histogram[b]++;
          } else {
            const t = (value(i) - lo) * scale;
            slice[y * tw + x] = toHalf(t);
            histogram[Math.min(255, Math.max(0, Math.floor(t * 256)))]++;
          }
        }
      }
      device.queue.writeTexture(
        { texture: this.texture, origin: [0, 0, z] },
        slice as Uint8Array<ArrayBuffer>,
        { bytesPerRow: tw * bpp, rowsPerImage: th },
        [tw, th, 1],
      );
    }

    // World box: voxel centres at index * spacing, so the box spans half a voxel beyond them.
    this.box = {
      min: [0, 1, 2].map((a) => -0.5 * v.spacing[a]) as Vec3,
      max: [0, 1, 2].map((a) => (v.dims[a] - 0.5) * v.spacing[a]) as Vec3,
    };
    this.refStep = Math.min(...v.spacing.map((s, a) => s * stride[a]));
    this.rebind();
    this.viewer.requestFrame();
    return {
      range: [lo, hi],
      histogram,
      textureDims: tdims,
      format,
      gpuBytes: tw * th * td * bpp,
      suggestedWindow: suggestWindow(histogram),
    };
  }

  clear(): void {
    this.texture?.destroy();
    this.texture = undefined;
    this.bindGroup = undefined;
    this.viewer.requestFrame();
  }

  private rebind(): void {
    if (!this.texture) return;
    this.bindGroup = this.viewer.device.createBindGroup({
      label: 'VolumeLayer.bindGroup',
      layout: this.layout,
      entries: [
        { binding: 0, resource: { buffer: this.uniforms } },
        { binding: 1, resource: this.texture.createView() },
        { binding: 2, resource: this.sampler },
        { binding: 3, resource: this.tfTexture.createView() },
        { binding: 4, resource: this.prepass.view },
      ],
    });
  }

  private writeUniforms(): void {
    if (!this.texture) return;
    const cam = this.viewer.camera;
    const f = this.f32;
    const u = this.u32;
    if (!mat4.invert(this.inverse, cam.viewProjection(this.viewProj))) mat4.identity(this.inverse);
    f.set(this.inverse as Float32Array, 0);
    const size = this.size;
    for (let a = 0; a < 3; a++) {
      size[a] = this.box.max[a] - this.box.min[a];
      f[16 + a] = this.box.min[a];
      f[20 + a] = size[a];
    }
    f[19] = 0;
    f[23] = 0;
    const step = this.refStep / this.quality;
    f[24] = step;
    f[25] = this.opacity;
    f[26] = this.window[0];
    f[27] = this.window[1];
    u[28] = this.mode === 'mip' ? 1 : 0;
    u[29] = Math.ceil(Math.hypot(size[0], size[1], size[2]) / step) + 2;
    u[30] = this.prepass.active ? 1 : 0;
    f[31] = this.refStep;
    this.viewer.device.queue.writeBuffer(this.uniforms, 0, this.scratch);
  }

  draw(pass: GPURenderPassEncoder): void {
    if (!this.visible || !this.bindGroup) return;
    pass.setPipeline(this.pipeline);
    pass.setBindGroup(1, this.bindGroup);
    pass.draw(36);
  }

  destroy(): void {
    this.texture?.destroy();
    this.tfTexture.destroy();
    this.uniforms.destroy();
  }
}

/** Window from the histogram: from the dominant background level to the 99.9th percentile. */
export function suggestWindow(histogram: Float64Array): [number, number] {
  let total = 0;
  for (const c of histogram) total += c;
  if (total === 0) return [0, 1];
  let mode = 0;
  for (let i = 1; i < histogram.length; i++) if (histogram[i] > histogram[mode]) mode = i;
  let seen = 0;
  let top = histogram.length - 1;
  for (let i = 0; i < histogram.length; i++) {
    seen += histogram[i];
    if (seen >= total * 0.999) {
      top = i;
      break;
    }
  }
  const lo = Math.min((mode + 1) / histogram.length, 0.9);
  const hi = Math.max((top + 1) / histogram.length, lo + 0.05);
  return [lo, Math.min(1, hi)];
}
