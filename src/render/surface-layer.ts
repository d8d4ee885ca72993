// Draws the isosurface: the welded compressed vertices of an
// IsosurfaceDrawData (position and normal interleaved) and its index shards
// (each with a GPU-written drawIndexedIndirect record), lit with smooth normals from the volume gradient
// (computed once per surface by the pipeline; see shaders/render/surface.wgsl),
// two-sided, with a headlight. Nothing is allocated per frame. Voxel
// (i, j, k) is drawn at ((i, j, k) + origin) * voxelSize; with `depthPrepass` it also
// draws its depth alone, for a volume renderer that stops its rays there.

import { vec3 } from 'gl-matrix';
import lightingWgsl from '../../shaders/render/lighting.wgsl?raw';
import surfaceWgsl from '../../shaders/render/surface.wgsl?raw';
import vertexFormatWgsl from '../../shaders/isosurface/vertex_format.wgsl?raw';
import { createShaderModule } from '../gpu/wgsl.ts';
import type { IsosurfaceDrawData } from '../isosurface/types.ts';
import type { ArcballCamera } from './camera.ts';
import { type Clip, clipPlanes } from '../core/clip.ts';
import { PEEL_TARGET, peelBindGroupLayout } from './depth-peel.ts';
import { DEPTH_FORMAT, frameSnippet, type RenderLayer } from './viewer.ts';

/** What a layer needs from the viewer (a Viewer satisfies it; tests build one without a canvas). */
export interface RenderTarget {
  readonly device: GPUDevice;
  readonly format: GPUTextureFormat;
  readonly frameBindGroupLayout: GPUBindGroupLayout;
  readonly camera: ArcballCamera;
}

export type Rgb = [number, number, number];

export interface SurfaceStyle {
  /** Outside of the value >= iso region (sRGB, 0..1). */
  front: Rgb;
  /** Inside (back faces). */
  back: Rgb;
  /** Normals from the volume gradient (true) or flat per triangle. */
  smooth: boolean;
  ambient: number;
  specular: number;
  rim: number;
  /** 0..1: how much far parts darken. */
  depthCue: number;
  /** 1: opaque; below 1 the surface is see-through (depth peeled: src/render/depth-peel.ts). */
  opacity: number;
}

export const DEFAULT_SURFACE_STYLE: SurfaceStyle = {
  front: [0.86, 0.8, 0.7],
  back: [0.42, 0.56, 0.74],
  smooth: true,
  ambient: 0.16,
  specular: 0.28,
  rim: 0.12,
  depthCue: 0.35,
  opacity: 1,
};

const UNIFORM_BYTES = 128 + 16 + 7 * 16;
const UNIT_SCALE = [1, 1, 1] as const;

/**
 * One piece of a surface made of several (a store refined by the view: one
 * per level): its draw data, drawn at `scale` (per axis) times the layer's
 * voxel size from `origin` (in its own voxels), tinted by `tint` (linear multiplier; the
 * level tint) when given.
 */
export interface SurfacePart {
  data: IsosurfaceDrawData;
  scale: readonly [number, number, number];
  origin: [number, number, number];
  tint?: Rgb;
}

export interface SurfaceLayerOptions {
  /** Also build the depth-only pipeline (drawDepth), for a depth pre-pass of opaque layers. */
  depthPrepass?: boolean;
}

export class SurfaceLayer implements RenderLayer {
  visible = true;
  style: SurfaceStyle = { ...DEFAULT_SURFACE_STYLE };
  /** World size of a voxel (a microscope stack's spacing); the main page draws in voxel units. */
  voxelSize: [number, number, number] = [1, 1, 1];
  /**
   * Where voxel (0, 0, 0) sits, in voxels of this surface: (i, j, k) is drawn
   * at ((i, j, k) + origin) * voxelSize. A store's coarse level sits at the
   * centre of the finer voxels it averages (its OME translation), e.g. 1.5 /
   * 4 = 0.375 of its own voxels for level 2.
   */
  origin: [number, number, number] = [0, 0, 0];
  #clip: Clip | undefined;
  #clipPlanes: [number, number, number, number][] = [];
  /** Cuts the surface open (level-0 voxel coordinates: src/core/clip.ts); drawn where every plane keeps it. */
  get clip(): Clip | undefined {
    return this.#clip;
  }
  set clip(clip: Clip | undefined) {
    this.#clip = clip;
    this.#clipPlanes = clipPlanes(clip);
  }
  private data: IsosurfaceDrawData | undefined;
  /** The single surface as its own scene for the depth cue (one object, reused: a frame allocates nothing). */
  private readonly singleScene: { data: IsosurfaceDrawData | undefined; scale: readonly number[]; origin: readonly number[] } = {
    data: undefined,
    scale: [1, 1, 1],
    origin: [0, 0, 0],
  };
  /** Several pieces instead of `data` (setParts): each with its own uniforms and bind group. */
  private parts: readonly SurfacePart[] | undefined;
  private readonly partUniforms: { buffer: GPUBuffer; bindGroup: GPUBindGroup }[] = [];
  private bindGroup: GPUBindGroup | undefined;
  private boundVersion = -1;
  private readonly uniforms: GPUBuffer;
  private readonly scratch = new ArrayBuffer(UNIFORM_BYTES);
  private readonly views = { u32: new Uint32Array(this.scratch), i32: new Int32Array(this.scratch), f32: new Float32Array(this.scratch) };
  private readonly centre = vec3.create();
  private readonly eye = vec3.create();

  private readonly pipeline: GPURenderPipeline;
  private readonly peelPipeline: GPURenderPipeline;
  private readonly layout: GPUBindGroupLayout;
  private readonly depthPipeline: GPURenderPipeline | undefined;

  private constructor(
    private readonly target: RenderTarget,
    pipelines: SurfacePipelines,
  ) {
    this.pipeline = pipelines.pipeline;
    this.peelPipeline = pipelines.peel;
    this.layout = pipelines.layout;
    this.depthPipeline = pipelines.depth;
    this.uniforms = target.device.createBuffer({
      label: 'SurfaceLayer.uniforms',
      size: UNIFORM_BYTES,
      usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
    });
  }

  static async create(target: RenderTarget, options: SurfaceLayerOptions = {}): Promise<SurfaceLayer> {
    return new SurfaceLayer(target, await surfacePipelines(target, options.depthPrepass === true));
  }

  /** The surface to draw (undefined: nothing). Bind groups follow `data.version`. */
  setDrawData(data: IsosurfaceDrawData | undefined): void {
    if (data !== this.data) {
      this.data = data;
      this.bindGroup = undefined;
      this.boundVersion = -1;
    }
  }

  get drawData(): IsosurfaceDrawData | undefined {
    return this.data;
  }

  /** Draws these pieces instead of the draw data (undefined: back to setDrawData's). */
  setParts(parts: readonly SurfacePart[] | undefined): void {
    this.parts = parts && parts.length > 0 ? parts : undefined;
  }

  private partUniform(i: number): { buffer: GPUBuffer; bindGroup: GPUBindGroup } {
    while (this.partUniforms.length <= i) {
      const buffer = this.target.device.createBuffer({
        label: `SurfaceLayer.part${this.partUniforms.length}.uniforms`,
        size: UNIFORM_BYTES,
        usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
      });
      const bindGroup = this.target.device.createBindGroup({
        label: `SurfaceLayer.part${this.partUniforms.length}.bindGroup`,
        layout: this.layout,
        entries: [{ binding: 0, resource: { buffer } }],
      });
      this.partUniforms.push({ buffer, bindGroup });
    }
    return this.partUniforms[i];
  }

  private ensureBindGroup(data: IsosurfaceDrawData): GPUBindGroup {
    if (!this.bindGroup || this.boundVersion !== data.version) {
      this.bindGroup = this.target.device.createBindGroup({
        label: 'SurfaceLayer.bindGroup',
        layout: this.layout,
        entries: [{ binding: 0, resource: { buffer: this.uniforms } }],
      });
      this.boundVersion = data.version;
    }
    return this.bindGroup;
  }

  /**
   * The uniforms of one piece (`scale` times the voxel size, from `origin`,
   * `tint`); the depth cue spans `scene`, the piece whose extent is the
   * volume's (the piece itself when it is the only one). Nothing allocated:
   * this runs for every piece at every frame.
   */
  private writeUniforms(
    data: IsosurfaceDrawData,
    into: GPUBuffer,
    scale: readonly number[],
    origin: readonly number[],
    tint: Rgb | undefined,
    scene: { data?: IsosurfaceDrawData; scale: readonly number[]; origin: readonly number[] },
  ): void {
    const sceneDims = (scene.data ?? data).info.dims;
    const s = this.style;
    const { u32, i32, f32 } = this.views;
    u32[0] = 0;
    u32[1] = 0;
    u32[2] = 0;
    u32[3] = s.smooth ? 1 : 0;
    i32[4] = data.info.dims[0];
    i32[5] = data.info.dims[1];
    i32[6] = data.info.dims[2];
    i32[7] = 0;
    f32[8] = s.front[0];
    f32[9] = s.front[1];
    f32[10] = s.front[2];
    f32[11] = s.ambient;
    f32[12] = s.back[0];
    f32[13] = s.back[1];
    f32[14] = s.back[2];
    f32[15] = s.specular;
    // Depth-cue range: the eye distance to the volume's bounding sphere (world space).
    let r2 = 0;
    for (let a = 0; a < 3; a++) {
      const size = this.voxelSize[a] * scene.scale[a];
      const extent = (sceneDims[a] - 1) * size;
      this.centre[a] = extent / 2 + scene.origin[a] * size;
      r2 += extent * extent;
    }
    const radius = 0.5 * Math.sqrt(r2);
    const eyeDist = vec3.distance(this.target.camera.eyePosition(this.eye), this.centre);
    f32[16] = s.rim;
    f32[17] = s.depthCue;
    f32[18] = Math.max(0, eyeDist - radius);
    f32[19] = eyeDist + radius;
    f32[20] = this.voxelSize[0] * scale[0];
    f32[21] = this.voxelSize[1] * scale[1];
    f32[22] = this.voxelSize[2] * scale[2];
    f32[23] = 0;
    f32[24] = origin[0];
    f32[25] = origin[1];
    f32[26] = origin[2];
    f32[27] = 0;
    f32[28] = tint ? tint[0] : 1;
    f32[29] = tint ? tint[1] : 1;
    f32[30] = tint ? tint[2] : 1;
    f32[31] = s.opacity;
    // the clip (level-0 voxel coordinates, n . x + w >= 0) in world space: x = world / voxel size - origin
    const planes = this.#clipPlanes;
    u32[32] = planes.length;
    for (let i = 0; i < planes.length; i++) {
      const [nx, ny, nz, w] = planes[i];
      const o = 36 + 4 * i;
      f32[o] = nx / this.voxelSize[0];
      f32[o + 1] = ny / this.voxelSize[1];
      f32[o + 2] = nz / this.voxelSize[2];
      f32[o + 3] = w - (nx * this.origin[0] + ny * this.origin[1] + nz * this.origin[2]);
    }
    this.target.device.queue.writeBuffer(into, 0, this.scratch);
  }

  /** Whether there is a surface to draw (DepthDrawer of a depth pre-pass). */
  get hasDepth(): boolean {
    return this.visible && ((this.data !== undefined && this.data.shards.length > 0) || this.parts !== undefined);
  }

  private drawWith(pass: GPURenderPassEncoder, pipeline: GPURenderPipeline): void {
    if (this.parts) {
      if (!this.visible) return;
      // the depth cue spans the whole scene: the piece of the largest voxels (the coarsest level covers the volume)
      let scene = this.parts[0];
      const volumeOf = (p: SurfacePart) => p.scale[0] * p.scale[1] * p.scale[2];
      for (const part of this.parts) if (volumeOf(part) > volumeOf(scene)) scene = part;
      pass.setPipeline(pipeline);
      for (let i = 0; i < this.parts.length; i++) {
        const part = this.parts[i];
        if (part.data.shards.length === 0) continue;
        const u = this.partUniform(i);
        this.writeUniforms(part.data, u.buffer, part.scale, part.origin, part.tint, scene);
        pass.setBindGroup(1, u.bindGroup);
        pass.setVertexBuffer(0, part.data.vertices);
        for (const shard of part.data.shards) {
          pass.setIndexBuffer(shard.indices, 'uint32');
          pass.drawIndexedIndirect(shard.drawArgs, shard.drawArgsOffset);
        }
      }
      return;
    }
    const data = this.data;
    if (!this.visible || !data || data.shards.length === 0) return;
    // Written at every draw (the camera moves); the pre-pass and the frame see the same values.
    this.singleScene.data = data;
    this.singleScene.origin = this.origin;
    this.writeUniforms(data, this.uniforms, UNIT_SCALE, this.origin, undefined, this.singleScene);
    pass.setPipeline(pipeline);
    pass.setBindGroup(1, this.ensureBindGroup(data));
    pass.setVertexBuffer(0, data.vertices);
    for (const shard of data.shards) {
      pass.setIndexBuffer(shard.indices, 'uint32');
      pass.drawIndexedIndirect(shard.drawArgs, shard.drawArgsOffset);
    }
  }

  /** See-through this frame: drawn by the depth peeling (drawPeel), not in the opaque pass. */
  get transparent(): boolean {
    return this.style.opacity < 1 && this.hasDepth;
  }

  draw(pass: GPURenderPassEncoder): void {
    if (!this.transparent) this.drawWith(pass, this.pipeline);
  }

  drawPeel(pass: GPURenderPassEncoder): void {
    if (this.transparent) this.drawWith(pass, this.peelPipeline);
  }

  /** Depth only, into a pass with a depth attachment and no colour target (needs `depthPrepass`). */
  drawDepth(pass: GPURenderPassEncoder): void {
    if (!this.depthPipeline) throw new Error('SurfaceLayer.drawDepth: create the layer with { depthPrepass: true }');
    this.drawWith(pass, this.depthPipeline);
  }

  destroy(): void {
    this.uniforms.destroy();
    for (const u of this.partUniforms) u.buffer.destroy();
    this.partUniforms.length = 0;
    this.parts = undefined;
    this.data = undefined;
    this.bindGroup = undefined;
  }
}

interface SurfacePipelines {
  pipeline: GPURenderPipeline;
  peel: GPURenderPipeline;
  depth: GPURenderPipeline | undefined;
  layout: GPUBindGroupLayout;
}

/** One set per device, target format and depth pre-pass: the page's several surfaces share them. */
const pipelineCache = new WeakMap<GPUDevice, Map<string, Promise<SurfacePipelines>>>();

function surfacePipelines(target: RenderTarget, depthPrepass: boolean): Promise<SurfacePipelines> {
  const { device } = target;
  let byKey = pipelineCache.get(device);
  if (!byKey) pipelineCache.set(device, (byKey = new Map()));
  const key = `${target.format} ${depthPrepass}`;
  let made = byKey.get(key);
  if (!made) {
    made = makeSurfacePipelines(target, depthPrepass);
    made.catch(() => byKey.delete(key));
    byKey.set(key, made);
  }
  return made;
}

async function makeSurfacePipelines(target: RenderTarget, depthPrepass: boolean): Promise<SurfacePipelines> {
  const { device } = target;
  const module = await createShaderModule(device, 'SurfaceLayer.shader', [
    frameSnippet,
    { name: 'shaders/isosurface/vertex_format.wgsl', code: vertexFormatWgsl },
    { name: 'shaders/render/lighting.wgsl', code: lightingWgsl },
    { name: 'shaders/render/surface.wgsl', code: surfaceWgsl },
  ]);
  const layout = device.createBindGroupLayout({
    label: 'SurfaceLayer.layout',
    entries: [{ binding: 0, visibility: GPUShaderStage.VERTEX | GPUShaderStage.FRAGMENT, buffer: { type: 'uniform' } }],
  });
  const pipelineLayout = device.createPipelineLayout({ label: 'SurfaceLayer', bindGroupLayouts: [target.frameBindGroupLayout, layout] });
  const peelLayout = device.createPipelineLayout({
    label: 'SurfaceLayer.peel',
    bindGroupLayouts: [target.frameBindGroupLayout, layout, peelBindGroupLayout(device)],
  });
  // The welded vertices, 12 bytes each: packed position and block id, then the normal.
  const position: GPUVertexAttribute = { shaderLocation: 0, offset: 0, format: 'uint32x2' };
  const normal: GPUVertexAttribute = { shaderLocation: 1, offset: 8, format: 'uint32' };
  const vertices: GPUVertexBufferLayout = { arrayStride: 12, stepMode: 'vertex', attributes: [position, normal] };
  const positions: GPUVertexBufferLayout = { arrayStride: 12, stepMode: 'vertex', attributes: [position] };
  // Two-sided: no culling; the fragment shader tells the sides apart.
  const primitive: GPUPrimitiveState = { topology: 'triangle-list', cullMode: 'none' };
  const depthStencil: GPUDepthStencilState = { format: DEPTH_FORMAT, depthWriteEnabled: true, depthCompare: 'less' };
  const [pipeline, peel, depth] = await Promise.all([
    device.createRenderPipelineAsync({
      label: 'SurfaceLayer.pipeline',
      layout: pipelineLayout,
      vertex: { module, entryPoint: 'vs', buffers: [vertices] },
      fragment: { module, entryPoint: 'fs', targets: [{ format: target.format }] },
      primitive,
      depthStencil,
    }),
    device.createRenderPipelineAsync({
      label: 'SurfaceLayer.peelPipeline',
      layout: peelLayout,
      vertex: { module, entryPoint: 'vs', buffers: [vertices] },
      fragment: { module, entryPoint: 'fs_peel', targets: [PEEL_TARGET.colour] },
      primitive,
      depthStencil: PEEL_TARGET.depth,
    }),
    depthPrepass
      ? device.createRenderPipelineAsync({
          label: 'SurfaceLayer.depthPipeline',
          layout: pipelineLayout,
          vertex: { module, entryPoint: 'vs_depth', buffers: [positions] },
          primitive,
          depthStencil,
        })
      : undefined,
  ]);
  return { pipeline, peel, depth, layout };
}
