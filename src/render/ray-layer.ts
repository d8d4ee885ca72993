// The isosurface ray cast in the block cache (shaders/render/raycast.wgsl;
// issue 46): no triangles. One full-viewport triangle per frame; each
// pixel's ray walks the volume's cells, skips the blocks the isovalue does
// not reach (their neighbourhood ranges), and finds the first crossing of
// the trilinear interpolant exactly (shaders/raycast/cell_root.wgsl) from
// the decoded blocks the surface's computation left in the cache
// (IsosurfaceDrawData.slotData, blockToSlot). Lit as the mesh is, depth
// written. The isovalue must be the one the cache was last computed for
// (the page passes the drawn surface's): the cache holds every block active
// at it. Opaque (see-through rays are not peeled yet); volumes opened whole.
import { mat4, vec3 } from 'gl-matrix';
import lightingWgsl from '../../shaders/render/lighting.wgsl?raw';
import raycastWgsl from '../../shaders/render/raycast.wgsl?raw';
import { type Clip, clipPlanes } from '../core/clip.ts';
import { createShaderModule } from '../gpu/wgsl.ts';
import type { IsosurfaceDrawData } from '../isosurface/types.ts';
import { cellRootSnippet } from '../raycast/cell-root-wgsl.ts';
import { DEFAULT_SURFACE_STYLE, type RenderTarget, type SurfaceStyle } from './surface-layer.ts';
import { DEPTH_FORMAT, frameSnippet, type RenderLayer } from './viewer.ts';

const UNIFORM_BYTES = 64 + 8 * 16 + 7 * 16;

export class RayLayer implements RenderLayer {
  visible = true;
  style: SurfaceStyle = { ...DEFAULT_SURFACE_STYLE };
  /** World size of a voxel, and where voxel (0, 0, 0) sits (in voxels), as the surface layer's. */
  voxelSize: [number, number, number] = [1, 1, 1];
  origin: [number, number, number] = [0, 0, 0];
  /** The isovalue the cache was computed for (the drawn surface's). */
  iso = Number.NaN;
  #clipPlanes: [number, number, number, number][] = [];
  #data: IsosurfaceDrawData | undefined;
  #bindGroup: GPUBindGroup | undefined;
  #boundVersion = -1;
  readonly #uniforms: GPUBuffer;
  readonly #scratch = new ArrayBuffer(UNIFORM_BYTES);
  readonly #f32 = new Float32Array(this.#scratch);
  readonly #i32 = new Int32Array(this.#scratch);
  readonly #u32 = new Uint32Array(this.#scratch);
  readonly #viewProj = mat4.create();
  readonly #inverse = mat4.create();
  readonly #eye = vec3.create();
  readonly #centre = [0, 0, 0];

  private constructor(
    private readonly target: RenderTarget,
    private readonly pipeline: GPURenderPipeline,
  ) {
    this.#uniforms = target.device.createBuffer({
      label: 'RayLayer.uniforms',
      size: UNIFORM_BYTES,
      usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
    });
  }

  static async create(target: RenderTarget): Promise<RayLayer> {
    const { device } = target;
    const module = await createShaderModule(device, 'RayLayer.shader', [
      frameSnippet,
      cellRootSnippet,
      { name: 'shaders/render/lighting.wgsl', code: lightingWgsl },
      { name: 'shaders/render/raycast.wgsl', code: raycastWgsl },
    ]);
    const storage = (binding: number): GPUBindGroupLayoutEntry => ({
      binding,
      visibility: GPUShaderStage.FRAGMENT,
      buffer: { type: 'read-only-storage' },
    });
    const layout = device.createBindGroupLayout({
      label: 'RayLayer.layout',
      entries: [{ binding: 0, visibility: GPUShaderStage.FRAGMENT, buffer: { type: 'uniform' } }, storage(1), storage(2), storage(3)],
    });
    const pipeline = await device.createRenderPipelineAsync({
      label: 'RayLayer.pipeline',
      layout: device.createPipelineLayout({ label: 'RayLayer', bindGroupLayouts: [target.frameBindGroupLayout, layout] }),
      vertex: { module, entryPoint: 'vs' },
      fragment: { module, entryPoint: 'fs', targets: [{ format: target.format }] },
      primitive: { topology: 'triangle-list', cullMode: 'none' },
      depthStencil: { format: DEPTH_FORMAT, depthWriteEnabled: true, depthCompare: 'less' },
    });
    return new RayLayer(target, pipeline);
  }

  /** The surface whose cache the rays read (a pipeline's own draw data: it has the neighbourhood ranges). */
  setDrawData(data: IsosurfaceDrawData | undefined): void {
    if (data !== this.#data) {
      this.#data = data;
      this.#bindGroup = undefined;
    }
  }

  /** Cuts the surface open (level-0 voxel coordinates): a hit the clip removes lets the ray go on. */
  set clip(clip: Clip | undefined) {
    this.#clipPlanes = clipPlanes(clip);
  }

  draw(pass: GPURenderPassEncoder): void {
    const data = this.#data;
    if (!this.visible || !data?.neighbourhoodRanges || !Number.isFinite(this.iso)) return;
    if (!this.#bindGroup || this.#boundVersion !== data.version) {
      this.#bindGroup = this.target.device.createBindGroup({
        label: 'RayLayer.bindGroup',
        layout: this.pipeline.getBindGroupLayout(1),
        entries: [
          { binding: 0, resource: { buffer: this.#uniforms } },
          { binding: 1, resource: { buffer: data.slotData } },
          { binding: 2, resource: { buffer: data.blockToSlot } },
          { binding: 3, resource: { buffer: data.neighbourhoodRanges } },
        ],
      });
      this.#boundVersion = data.version;
    }
    this.#writeUniforms(data);
    pass.setPipeline(this.pipeline);
    pass.setBindGroup(1, this.#bindGroup);
    pass.draw(3);
  }

  /** Written at every draw (the camera moves); nothing allocated. */
  #writeUniforms(data: IsosurfaceDrawData): void {
    const { camera } = this.target;
    const f32 = this.#f32,
      i32 = this.#i32,
      u32 = this.#u32;
    camera.viewProjection(this.#viewProj);
    mat4.invert(this.#inverse, this.#viewProj);
    f32.set(this.#inverse, 0);
    const { dims } = data.info;
    const s = this.style;
    let r2 = 0;
    const centre = this.#centre;
    for (let a = 0; a < 3; a++) {
      i32[16 + a] = dims[a];
      u32[20 + a] = Math.ceil(dims[a] / 4);
      const extent = (dims[a] - 1) * this.voxelSize[a];
      centre[a] = extent / 2 + this.origin[a] * this.voxelSize[a];
      r2 += extent * extent;
    }
    i32[19] = 0;
    u32[23] = 0;
    for (let a = 0; a < 3; a++) {
      f32[24 + a] = s.front[a];
      f32[28 + a] = s.back[a];
    }
    f32[27] = s.ambient;
    f32[31] = s.specular;
    // depth cue over the volume's bounding sphere, as the surface layer's
    camera.eyePosition(this.#eye);
    const eyeDist = Math.hypot(this.#eye[0] - centre[0], this.#eye[1] - centre[1], this.#eye[2] - centre[2]);
    const radius = 0.5 * Math.sqrt(r2);
    f32[32] = s.rim;
    f32[33] = s.depthCue;
    f32[34] = Math.max(0, eyeDist - radius);
    f32[35] = eyeDist + radius;
    f32[36] = this.voxelSize[0];
    f32[37] = this.voxelSize[1];
    f32[38] = this.voxelSize[2];
    f32[39] = this.iso;
    f32[40] = this.origin[0];
    f32[41] = this.origin[1];
    f32[42] = this.origin[2];
    f32[43] = 0;
    // the clip in world space, as the surface layer's
    const planes = this.#clipPlanes;
    u32[44] = planes.length;
    for (let i = 0; i < planes.length; i++) {
      const [nx, ny, nz, w] = planes[i];
      const o = 48 + 4 * i;
      f32[o] = nx / this.voxelSize[0];
      f32[o + 1] = ny / this.voxelSize[1];
      f32[o + 2] = nz / this.voxelSize[2];
      f32[o + 3] = w - (nx * this.origin[0] + ny * this.origin[1] + nz * this.origin[2]);
    }
    this.target.device.queue.writeBuffer(this.#uniforms, 0, this.#scratch);
  }

  destroy(): void {
    this.#uniforms.destroy();
    this.#data = undefined;
    this.#bindGroup = undefined;
  }
}
