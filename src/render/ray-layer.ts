// The isosurface ray cast in the block cache (shaders/render/raycast.wgsl;
// issue 46): no triangles. One full-viewport triangle per frame; each
// pixel's ray walks the volume's cells, skips the blocks the isovalue does
// not reach (their neighbourhood ranges), and finds the first crossing of
// the trilinear interpolant exactly (shaders/raycast/cell_root.wgsl) from
// the decoded blocks the surface's computation left in the cache
// (IsosurfaceDrawData.slotData, blockToSlot). Lit as the mesh is, depth
// written. The isovalue must be the one the cache was last computed for
// (the page passes the drawn surface's): the cache holds every block active
// at it. Opaque (see-through rays are not peeled yet). A volume opened whole
// is one draw (setDrawData); a store's step is one draw per level
// (setLevels: each level's pool and cache, only over the regions of the
// step it owns, by the step's region grid; shaders/render/ray_blocks_pool.wgsl),
// the depth test keeping the nearest level's hit, so a ray leaving a level-0
// brick for a level-2 brick goes on in level 2.
import { mat4, vec3 } from 'gl-matrix';
import lightingWgsl from '../../shaders/render/lighting.wgsl?raw';
import rayBlocksPoolWgsl from '../../shaders/render/ray_blocks_pool.wgsl?raw';
import rayBlocksStreamWgsl from '../../shaders/render/ray_blocks_stream.wgsl?raw';
import raycastWgsl from '../../shaders/render/raycast.wgsl?raw';
import { type Clip, clipPlanes } from '../core/clip.ts';
import { createShaderModule } from '../gpu/wgsl.ts';
import type { IsosurfaceDrawData } from '../isosurface/types.ts';
import { cellRootSnippet } from '../raycast/cell-root-wgsl.ts';
import { FINER_REACH_MARGIN, FINER_REACH_PER_VOXEL } from '../raycast/seam-reach.ts';
import { DEFAULT_SURFACE_STYLE, type RenderTarget, type SurfaceStyle } from './surface-layer.ts';
import { DEPTH_FORMAT, frameSnippet, type RenderLayer } from './viewer.ts';

const UNIFORM_BYTES = 64 + 8 * 16 + 7 * 16 + 6 * 16;

/** One level of a store's step, as the rays read it. */
export interface RayLevel {
  /** The store's level (which regions of the step's grid it owns). */
  level: number;
  /** The level's surface's own draw data (its cache, computed last at `iso`; the neighbourhood ranges). */
  data: IsosurfaceDrawData;
  /** The level's pool: its tables (ChunkedVolume.tables), chunks per axis, blocks per chunk edge. */
  tables: GPUBuffer;
  chunkGrid: readonly [number, number, number];
  chunkBlocks: number;
  /** Where the level's voxel j lies in level-0 voxels: j * scale + offset. */
  scale: readonly [number, number, number];
  offset: readonly [number, number, number];
  /** Multiplies the surface's colours (the tint-by-level view); default none. */
  tint?: readonly [number, number, number];
  /** Cells the rays reach above the level's own regions into coarser ones (from its ghosts; seamReachCells). */
  reachCells: number;
}

/**
 * The cells a level's rays reach above its drawn chunks so that no coarser
 * level's seam shows background: a level L's voxel centres sit
 * (2^(L-l) - 1) / 2 level-l voxels above level l's (OME translations of
 * averaged levels), so its region starts that far past the end of level l's;
 * a quarter of a cell more keeps the rays' boundary tests off the seam.
 */
export function seamReachCells(level: number, coarsest: number): number {
  if (coarsest <= level) return 0;
  return Math.ceil((2 ** (coarsest - level) - 1) / 2 + 0.25);
}

/**
 * Which level draws each region of a store's step (src/store/view/regions.ts
 * makes it from the step's leaves): a grid of cells `edge` level-0 voxels
 * wide, one byte per cell (x fastest), the owning level or 255.
 */
export interface RayRegions {
  grid: readonly [number, number, number];
  edge: readonly [number, number, number];
  owner: Uint8Array;
}

/** What a store's shown level gives the rays: its level, pool and surface (a step's CutLevelShown). */
export interface RayLevelSource {
  level: number;
  volume: { tables: GPUBuffer; layout: { chunkGrid: readonly [number, number, number] }; chunkBlocks: number };
  surface: { drawData: IsosurfaceDrawData };
}

/**
 * A step's levels as the rays read them: each placed at its OME scale and
 * offset (`levelScales`, `levelOffsets` in level-0 voxels), reaching into
 * its ghosts toward the step's coarsest level, tinted by `tints[i]` if given.
 */
export function rayLevelsOf(
  levels: readonly RayLevelSource[],
  levelScales: readonly (readonly [number, number, number])[],
  levelOffsets: readonly (readonly [number, number, number])[],
  tints?: readonly (readonly [number, number, number] | undefined)[],
): RayLevel[] {
  const coarsest = Math.max(...levels.map((l) => l.level));
  return levels.map((l, i) => ({
    level: l.level,
    data: l.surface.drawData,
    tables: l.volume.tables,
    chunkGrid: l.volume.layout.chunkGrid,
    chunkBlocks: l.volume.chunkBlocks,
    scale: levelScales[l.level],
    offset: levelOffsets[l.level],
    reachCells: seamReachCells(l.level, coarsest),
    ...(tints?.[i] ? { tint: tints[i] } : {}),
  }));
}

/** What one draw reads: a whole volume (no pool) or a level. */
interface RayPart {
  data: IsosurfaceDrawData;
  level?: RayLevel;
  uniforms: GPUBuffer;
  bindGroup?: GPUBindGroup;
  boundVersion: number;
  boundData?: IsosurfaceDrawData;
  boundTables?: GPUBuffer;
}

export class RayLayer implements RenderLayer {
  visible = true;
  style: SurfaceStyle = { ...DEFAULT_SURFACE_STYLE };
  /** World size of a level-0 voxel, and where voxel (0, 0, 0) sits (in voxels), as the surface layer's. */
  voxelSize: [number, number, number] = [1, 1, 1];
  origin: [number, number, number] = [0, 0, 0];
  /** The isovalue the caches were computed for (the drawn surface's). */
  iso = Number.NaN;
  #clipPlanes: [number, number, number, number][] = [];
  /** A volume opened whole (setDrawData), or a store's levels (setLevels). */
  #data: IsosurfaceDrawData | undefined;
  #levels: readonly RayLevel[] = [];
  #regions: RayRegions | undefined;
  /** The regions on the GPU (packed 4 to a word), grown, never shrunk while alive. */
  #regionBuffer: GPUBuffer | undefined;
  #regionsUploaded: RayRegions | undefined;
  /** Level-0 voxels per axis of a store (the depth cue's sphere); a whole volume's are its own. */
  #extent: readonly [number, number, number] | undefined;
  /** Uniform buffers and bind groups per draw, kept between frames (grown, never shrunk while alive). */
  readonly #parts: RayPart[] = [];
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
    private readonly wholePipeline: GPURenderPipeline,
    private readonly poolPipeline: GPURenderPipeline,
  ) {}

  static async create(target: RenderTarget): Promise<RayLayer> {
    const { device } = target;
    const storage = (binding: number): GPUBindGroupLayoutEntry => ({
      binding,
      visibility: GPUShaderStage.FRAGMENT,
      buffer: { type: 'read-only-storage' },
    });
    const uniform: GPUBindGroupLayoutEntry = { binding: 0, visibility: GPUShaderStage.FRAGMENT, buffer: { type: 'uniform' } };
    const pipelineOf = async (blocks: { name: string; code: string }, pool: boolean) => {
      const label = pool ? 'RayLayer.pool' : 'RayLayer';
      const module = await createShaderModule(device, `${label}.shader`, [
        frameSnippet,
        cellRootSnippet,
        { name: 'shaders/render/lighting.wgsl', code: lightingWgsl },
        { name: 'shaders/render/raycast.wgsl', code: raycastWgsl },
        blocks,
      ]);
      const layout = device.createBindGroupLayout({
        label: `${label}.layout`,
        entries: [uniform, storage(1), storage(2), storage(3), ...(pool ? [storage(4), storage(5)] : [])],
      });
      return device.createRenderPipelineAsync({
        label: `${label}.pipeline`,
        layout: device.createPipelineLayout({ label, bindGroupLayouts: [target.frameBindGroupLayout, layout] }),
        vertex: { module, entryPoint: 'vs' },
        fragment: { module, entryPoint: 'fs', targets: [{ format: target.format }] },
        primitive: { topology: 'triangle-list', cullMode: 'none' },
        depthStencil: { format: DEPTH_FORMAT, depthWriteEnabled: true, depthCompare: 'less' },
      });
    };
    const [whole, pool] = await Promise.all([
      pipelineOf({ name: 'shaders/render/ray_blocks_stream.wgsl', code: rayBlocksStreamWgsl }, false),
      pipelineOf({ name: 'shaders/render/ray_blocks_pool.wgsl', code: rayBlocksPoolWgsl }, true),
    ]);
    return new RayLayer(target, whole, pool);
  }

  /** The surface whose cache the rays read (a pipeline's own draw data: it has the neighbourhood ranges); replaces levels. */
  setDrawData(data: IsosurfaceDrawData | undefined): void {
    this.#data = data;
    this.#levels = [];
    this.#extent = undefined;
  }

  /**
   * A store's step: each level's pool and cache (every level computed last
   * at `iso`), in level-0 voxels of `extent` per axis, each drawn over the
   * step's `regions` it owns; replaces a whole volume.
   */
  setLevels(levels: readonly RayLevel[], extent: readonly [number, number, number], regions: RayRegions): void {
    this.#data = undefined;
    this.#levels = levels;
    this.#extent = extent;
    this.#regions = regions;
  }

  /** Whether there is something to draw (a surface or levels with their ranges). */
  get hasVolume(): boolean {
    return this.#data?.neighbourhoodRanges !== undefined || this.#levels.length > 0;
  }

  /** Cuts the surface open (level-0 voxel coordinates): a hit the clip removes lets the ray go on. */
  set clip(clip: Clip | undefined) {
    this.#clipPlanes = clipPlanes(clip);
  }

  draw(pass: GPURenderPassEncoder): void {
    if (!this.visible || !Number.isFinite(this.iso)) return;
    const whole = this.#data;
    if (whole) {
      if (!whole.neighbourhoodRanges) return;
      this.#drawPart(pass, 0, whole, undefined);
      return;
    }
    if (this.#levels.length > 0) this.#uploadRegions();
    this.#levels.forEach((l, k) => {
      if (l.data.neighbourhoodRanges) this.#drawPart(pass, k, l.data, l);
    });
  }

  /** The step's region grid into its buffer, once per setLevels. */
  #uploadRegions(): void {
    const regions = this.#regions!;
    if (this.#regionsUploaded === regions) return;
    const bytes = Math.max(4, Math.ceil(regions.owner.length / 4) * 4);
    if (!this.#regionBuffer || this.#regionBuffer.size < bytes) {
      this.#regionBuffer?.destroy();
      this.#regionBuffer = this.target.device.createBuffer({
        label: 'RayLayer.regionOwner',
        size: bytes,
        usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST,
      });
      // bind groups name the buffer: made again
      for (const p of this.#parts) p.bindGroup = undefined;
    }
    const packed = new Uint8Array(bytes);
    packed.set(regions.owner);
    this.target.device.queue.writeBuffer(this.#regionBuffer, 0, packed);
    this.#regionsUploaded = regions;
  }

  #drawPart(pass: GPURenderPassEncoder, k: number, data: IsosurfaceDrawData, level: RayLevel | undefined): void {
    const { device } = this.target;
    let part = this.#parts[k];
    if (!part) {
      part = {
        data,
        uniforms: device.createBuffer({
          label: `RayLayer.uniforms[${k}]`,
          size: UNIFORM_BYTES,
          usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
        }),
        boundVersion: -1,
      };
      this.#parts[k] = part;
    }
    const pipeline = level ? this.poolPipeline : this.wholePipeline;
    if (!part.bindGroup || part.boundData !== data || part.boundVersion !== data.version || part.boundTables !== level?.tables) {
      part.bindGroup = device.createBindGroup({
        label: `RayLayer.bindGroup[${k}]`,
        layout: pipeline.getBindGroupLayout(1),
        entries: [
          { binding: 0, resource: { buffer: part.uniforms } },
          { binding: 1, resource: { buffer: data.slotData } },
          { binding: 2, resource: { buffer: data.blockToSlot } },
          { binding: 3, resource: { buffer: data.neighbourhoodRanges! } },
          ...(level
            ? [
                { binding: 4, resource: { buffer: level.tables } },
                { binding: 5, resource: { buffer: this.#regionBuffer! } },
              ]
            : []),
        ],
      });
      part.boundData = data;
      part.boundVersion = data.version;
      part.boundTables = level?.tables;
    }
    this.#writeUniforms(part.uniforms, data, level);
    pass.setPipeline(pipeline);
    pass.setBindGroup(1, part.bindGroup);
    pass.draw(3);
  }

  /** Written at every draw (the camera moves); nothing allocated. */
  #writeUniforms(buffer: GPUBuffer, data: IsosurfaceDrawData, level: RayLevel | undefined): void {
    const { camera } = this.target;
    const f32 = this.#f32,
      i32 = this.#i32,
      u32 = this.#u32;
    camera.viewProjection(this.#viewProj);
    mat4.invert(this.#inverse, this.#viewProj);
    f32.set(this.#inverse, 0);
    const { dims } = data.info;
    const extent = this.#extent ?? dims;
    const s = this.style;
    let r2 = 0;
    const centre = this.#centre;
    for (let a = 0; a < 3; a++) {
      i32[16 + a] = dims[a];
      u32[20 + a] = Math.ceil(dims[a] / 4);
      const size = (extent[a] - 1) * this.voxelSize[a];
      centre[a] = size / 2 + this.origin[a] * this.voxelSize[a];
      r2 += size * size;
    }
    i32[19] = 0;
    u32[23] = 0;
    for (let a = 0; a < 3; a++) {
      const tint = level?.tint?.[a] ?? 1;
      f32[24 + a] = s.front[a] * tint;
      f32[28 + a] = s.back[a] * tint;
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
    // the drawn voxels in the world: a level's voxel j at (j * scale + offset + origin) * voxel size,
    // that is (j + (offset + origin) / scale) * (voxel size * scale)
    for (let a = 0; a < 3; a++) {
      const scale = level?.scale[a] ?? 1;
      f32[36 + a] = this.voxelSize[a] * scale;
      f32[40 + a] = ((level?.offset[a] ?? 0) + this.origin[a]) / scale;
    }
    f32[39] = this.iso;
    f32[43] = 0;
    // the clip in world space, as the surface layer's
    const planes = this.#clipPlanes;
    u32[44] = planes.length;
    for (let i = 0; i < 7; i++) {
      const o = 48 + 4 * i;
      const plane = planes[i];
      if (!plane) {
        f32.fill(0, o, o + 4);
        continue;
      }
      const [nx, ny, nz, w] = plane;
      f32[o] = nx / this.voxelSize[0];
      f32[o + 1] = ny / this.voxelSize[1];
      f32[o + 2] = nz / this.voxelSize[2];
      f32[o + 3] = w - (nx * this.origin[0] + ny * this.origin[1] + nz * this.origin[2]);
    }
    // a level's pool (ray_blocks_pool.wgsl)
    const grid = level?.chunkGrid ?? [0, 0, 0];
    u32[76] = grid[0];
    u32[77] = grid[1];
    u32[78] = grid[2];
    u32[79] = grid[0] * grid[1] * grid[2];
    u32[80] = level?.chunkBlocks ?? 0;
    u32[81] = level?.reachCells ?? 0;
    u32[82] = 0;
    u32[83] = 0;
    // the step's regions this level owns (ray_blocks_pool.wgsl)
    const regions = this.#regions;
    for (let a = 0; a < 3; a++) {
      u32[84 + a] = level && regions ? regions.grid[a] : 0;
      f32[88 + a] = level && regions ? regions.edge[a] : 1;
      f32[92 + a] = level?.scale[a] ?? 1;
      f32[96 + a] = level?.offset[a] ?? 0;
    }
    u32[87] = level?.level ?? 0;
    f32[91] = 0;
    // how far a coarser level traces into a finer region below one it owns (finerReachVoxels)
    f32[95] = FINER_REACH_PER_VOXEL;
    f32[99] = FINER_REACH_MARGIN;
    this.target.device.queue.writeBuffer(buffer, 0, this.#scratch);
  }

  destroy(): void {
    for (const p of this.#parts) p.uniforms.destroy();
    this.#parts.length = 0;
    this.#regionBuffer?.destroy();
    this.#regionBuffer = undefined;
    this.#regionsUploaded = undefined;
    this.#regions = undefined;
    this.#data = undefined;
    this.#levels = [];
  }
}
