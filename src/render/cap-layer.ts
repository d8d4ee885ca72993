// Caps on a cut-open volume (shaders/render/cap.wgsl): per clip plane, the
// polygon where it cuts the volume's box and the other planes keep it
// (src/core/clip.ts capPolygons), drawn opaque in the volume's colours
// wherever the value there is at least the threshold. The blocks near the
// caps are decoded from the stream by the zfp decoder the cache uses, once
// per clip (a slab per plane: about 2 block layers), into buffers of this
// layer; a new threshold or colour range only rewrites the uniforms. A
// store's caps come in pieces, one per level of the step on screen: each
// decoded from that level's pool (the blocks of its resident chunks, named
// by slot), drawn at the level's scale and place, and only over the cells of
// the chunks that level draws (the cut's regions do not overlap).
import capWgsl from '../../shaders/render/cap.wgsl?raw';
import { type Clip, capBlocks, capPolygons } from '../core/clip.ts';
import { createShaderModule } from '../gpu/wgsl.ts';
import { ZfpDecoder } from '../zfp/decoder.ts';
import type { BlockSource } from '../zfp/gpu-stream.ts';
import type { RenderTarget } from './surface-layer.ts';
import { DEPTH_FORMAT, frameSnippet, type RenderLayer } from './viewer.ts';

const UNIFORM_BYTES = 80;

/** One piece of the caps: a volume (a level) and the clip in its voxels. */
export interface CapPiece {
  source: BlockSource;
  /** The clip in the source's voxel coordinates (core/clip.ts clipInLevel). */
  clip: Clip;
  /** The decoder's name of a block given its raster index (a pool: chunkBlockId); undefined: not decodable (left out). Default: the index. */
  idOf?: (block: number) => number | undefined;
  /** Whether the piece draws the cells of a block (a level draws only its own regions). Default: every block. */
  owns?: (block: number) => boolean;
  /** Where its blocks can be (block-index ranges, inclusive: a store level's resident chunks); default the whole volume. */
  within?: readonly { lo: readonly number[]; hi: readonly number[] }[];
  /** Level-0 voxels one of its voxels spans, and where its voxel (0, 0, 0) lies in level-0 voxels. */
  scale?: readonly [number, number, number];
  offset?: readonly [number, number, number];
}

interface PieceBuffers {
  dims: readonly number[];
  grid: readonly number[];
  scale: readonly number[];
  offset: readonly number[];
  vertices: GPUBuffer;
  vertexCount: number;
  blocks: GPUBuffer;
  values: GPUBuffer;
  owned: GPUBuffer;
  listed: number;
  uniforms: GPUBuffer;
  bindGroup: GPUBindGroup;
}

export class CapLayer implements RenderLayer {
  visible = true;
  /** World size of a level-0 voxel and where voxel (0, 0, 0) sits (as the surface layer's). */
  voxelSize: [number, number, number] = [1, 1, 1];
  origin: [number, number, number] = [0, 0, 0];
  /** Drawn where the value is at least this (the outermost surface's isovalue). */
  threshold = 0;
  /** The values the colour map spans. */
  range: [number, number] = [0, 1];

  #pieces: PieceBuffers[] = [];
  readonly #scratch = new ArrayBuffer(UNIFORM_BYTES);
  readonly #i32 = new Int32Array(this.#scratch);
  readonly #u32 = new Uint32Array(this.#scratch);
  readonly #f32 = new Float32Array(this.#scratch);

  private constructor(
    private readonly device: GPUDevice,
    private readonly pipeline: GPURenderPipeline,
    private readonly decoder: ZfpDecoder,
  ) {}

  static async create(target: RenderTarget): Promise<CapLayer> {
    const { device } = target;
    const module = await createShaderModule(device, 'CapLayer.shader', [frameSnippet, { name: 'shaders/render/cap.wgsl', code: capWgsl }]);
    const fragmentStorage = (binding: number): GPUBindGroupLayoutEntry => ({
      binding,
      visibility: GPUShaderStage.FRAGMENT,
      buffer: { type: 'read-only-storage' },
    });
    const layout = device.createBindGroupLayout({
      label: 'CapLayer.layout',
      entries: [
        { binding: 0, visibility: GPUShaderStage.VERTEX | GPUShaderStage.FRAGMENT, buffer: { type: 'uniform' } },
        fragmentStorage(1),
        fragmentStorage(2),
        fragmentStorage(3),
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

  /** Bytes the caps hold on the GPU (polygons, decoded blocks and their lists). */
  get byteSize(): number {
    return this.#pieces.reduce((a, p) => a + p.vertices.size + p.blocks.size + p.values.size + p.owned.size, 0);
  }

  /** Blocks decoded for the caps now. */
  get blocks(): number {
    return this.#pieces.reduce((a, p) => a + p.listed, 0);
  }

  /** Pieces drawn now. */
  get pieces(): number {
    return this.#pieces.length;
  }

  /**
   * The caps of `clip` on `stream`'s volume (undefined: none): polygons made
   * and the blocks near them decoded now (on the GPU, in queue order), when
   * they fit `maxBytes`; else none, and why.
   */
  setClip(stream: BlockSource | undefined, clip: Clip | undefined, maxBytes = Number.POSITIVE_INFINITY): string | null {
    return this.setPieces(stream && clip ? [{ source: stream, clip }] : [], maxBytes);
  }

  /** The caps of several pieces (a store's levels), all or none within `maxBytes`; why none, or null. */
  setPieces(pieces: readonly CapPiece[], maxBytes = Number.POSITIVE_INFINITY): string | null {
    this.#release();
    const plans = pieces.map((p) => this.#plan(p));
    const needed = plans.reduce((a, p) => a + (p ? 264 * p.ids.length + 4 * p.triangles.length : 0), 0);
    const blocks = plans.reduce((a, p) => a + (p?.ids.length ?? 0), 0);
    if (needed > maxBytes)
      return `the caps need ${(needed / 2 ** 20).toFixed(1)} MiB for the ${blocks.toLocaleString('en-US')} blocks along the cut, more than the GPU memory budget leaves (${(Math.max(0, maxBytes) / 2 ** 20).toFixed(1)} MiB)`;
    plans.forEach((plan, i) => {
      if (plan) this.#pieces.push(this.#make(pieces[i], plan));
    });
    return null;
  }

  /** A piece's polygons (triangles) and the blocks its samples read that can be decoded; null: no cap. */
  #plan(piece: CapPiece): { triangles: number[]; ids: number[]; decoderIds: number[]; owned: number[] } | null {
    const { dims } = piece.source.info;
    const caps = capPolygons(piece.clip, dims);
    if (caps.length === 0) return null;
    const triangles: number[] = [];
    for (const cap of caps) {
      for (let i = 1; i + 1 < cap.corners.length; i++) triangles.push(...cap.corners[0], ...cap.corners[i], ...cap.corners[i + 1]);
    }
    const ids: number[] = [];
    const decoderIds: number[] = [];
    const owned: number[] = [];
    for (const id of capBlocks(caps, dims, piece.within)) {
      const named = piece.idOf ? piece.idOf(id) : id;
      if (named === undefined) continue;
      ids.push(id);
      decoderIds.push(named);
      owned.push(!piece.owns || piece.owns(id) ? 1 : 0);
    }
    return { triangles, ids, decoderIds, owned };
  }

  #make(piece: CapPiece, plan: { triangles: number[]; ids: number[]; decoderIds: number[]; owned: number[] }): PieceBuffers {
    const { device } = this;
    const make = (label: string, size: number, usage: number) =>
      device.createBuffer({ label: `CapLayer.${label}`, size: Math.max(16, size), usage });
    const vertices = make('vertices', 4 * plan.triangles.length, GPUBufferUsage.VERTEX | GPUBufferUsage.COPY_DST);
    device.queue.writeBuffer(vertices, 0, Float32Array.from(plan.triangles));
    const storage = GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST | GPUBufferUsage.COPY_SRC;
    const n = plan.ids.length;
    const blocks = make('blocks', 4 * n, storage);
    device.queue.writeBuffer(blocks, 0, Uint32Array.from(plan.ids));
    const owned = make('owned', 4 * n, storage);
    device.queue.writeBuffer(owned, 0, Uint32Array.from(plan.owned));
    const values = make('values', 256 * n, storage);
    if (n > 0) {
      // slot k of the decoded values is listed block k, decoded under the source's name for it
      const decodeIds = make('decodeIds', 4 * n, storage);
      device.queue.writeBuffer(decodeIds, 0, Uint32Array.from(plan.decoderIds));
      const slots = make('slots', 4 * n, storage);
      device.queue.writeBuffer(
        slots,
        0,
        Uint32Array.from({ length: n }, (_, k) => k),
      );
      const count = make('count', 16, storage);
      device.queue.writeBuffer(count, 0, Uint32Array.of(n));
      const encoder = device.createCommandEncoder({ label: 'CapLayer.decode' });
      this.decoder.encodeDecodeBlocks(encoder, {
        stream: piece.source,
        blockIds: decodeIds,
        slotIds: slots,
        count: { buffer: count, offset: 0 },
        slots: values,
      });
      device.queue.submit([encoder.finish()]);
      for (const b of [decodeIds, slots, count]) b.destroy();
    }
    const uniforms = device.createBuffer({
      label: 'CapLayer.uniforms',
      size: UNIFORM_BYTES,
      usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
    });
    const bindGroup = device.createBindGroup({
      label: 'CapLayer.bindGroup',
      layout: this.pipeline.getBindGroupLayout(1),
      entries: [
        { binding: 0, resource: { buffer: uniforms } },
        { binding: 1, resource: { buffer: blocks } },
        { binding: 2, resource: { buffer: values } },
        { binding: 3, resource: { buffer: owned } },
      ],
    });
    const { dims, blockGrid } = piece.source.info;
    return {
      dims: [...dims],
      grid: [...blockGrid],
      scale: piece.scale ?? [1, 1, 1],
      offset: piece.offset ?? [0, 0, 0],
      vertices,
      vertexCount: plan.triangles.length / 3,
      blocks,
      values,
      owned,
      listed: n,
      uniforms,
      bindGroup,
    };
  }

  draw(pass: GPURenderPassEncoder): void {
    if (!this.visible || this.#pieces.length === 0) return;
    const i32 = this.#i32,
      u32 = this.#u32,
      f32 = this.#f32;
    pass.setPipeline(this.pipeline);
    for (const p of this.#pieces) {
      if (p.vertexCount === 0) continue;
      for (let a = 0; a < 3; a++) {
        i32[a] = p.dims[a];
        u32[4 + a] = p.grid[a];
        // a level's voxel spans scale level-0 voxels; its voxel 0 lies at offset: world = (x + origin) * size
        f32[8 + a] = this.voxelSize[a] * p.scale[a];
        f32[12 + a] = (this.origin[a] + p.offset[a]) / p.scale[a];
      }
      i32[3] = p.listed;
      f32[11] = this.threshold;
      f32[16] = this.range[0];
      f32[17] = this.range[1];
      this.device.queue.writeBuffer(p.uniforms, 0, this.#scratch);
      pass.setBindGroup(1, p.bindGroup);
      pass.setVertexBuffer(0, p.vertices);
      pass.draw(p.vertexCount);
    }
  }

  #release(): void {
    for (const p of this.#pieces) for (const b of [p.vertices, p.blocks, p.values, p.owned, p.uniforms]) b.destroy();
    this.#pieces = [];
  }

  destroy(): void {
    this.#release();
    this.decoder.destroy();
  }
}
