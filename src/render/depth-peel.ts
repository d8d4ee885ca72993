// Order-independent transparency by depth peeling (Everitt 2001): see-through
// layers are drawn `layers` times; pass k keeps, per pixel, the nearest
// fragment behind the one pass k - 1 kept (and in front of the opaque
// scene), and that layer goes under what the passes before accumulated. The
// result is exact back-to-front compositing of the first `layers` surfaces a
// ray crosses, whatever the triangle order (two nested closed surfaces are 4
// layers; the default 8 leaves room for folds). The accumulation then goes
// over the opaque image. Made once per device and target format; its
// textures follow the target's size.
import peelWgsl from '../../shaders/render/peel.wgsl?raw';
import { createShaderModule } from '../gpu/wgsl.ts';
import type { RenderLayer } from './layer.ts';

/** Depth of every target the viewer draws (opaque pass and peels): float32, so a peeled depth compares exactly with the fragment's. */
export const PEEL_DEPTH_FORMAT: GPUTextureFormat = 'depth32float';
const LAYER_FORMAT: GPUTextureFormat = 'rgba16float';

const peelLayouts = new WeakMap<GPUDevice, GPUBindGroupLayout>();

/** Bind group 2 of a layer's peel pipeline: the depth peeled before, the opaque depth (shaders/render/surface.wgsl). */
export function peelBindGroupLayout(device: GPUDevice): GPUBindGroupLayout {
  let layout = peelLayouts.get(device);
  if (!layout) {
    layout = device.createBindGroupLayout({
      label: 'DepthPeeler.peelLayout',
      entries: [0, 1].map((binding) => ({ binding, visibility: GPUShaderStage.FRAGMENT, texture: { sampleType: 'depth' as const } })),
    });
    peelLayouts.set(device, layout);
  }
  return layout;
}

/** The colour target of a peel pass and the depth state a layer's peel pipeline uses. */
export const PEEL_TARGET: { colour: GPUColorTargetState; depth: GPUDepthStencilState } = {
  colour: { format: LAYER_FORMAT },
  depth: { format: PEEL_DEPTH_FORMAT, depthWriteEnabled: true, depthCompare: 'less' },
};

export interface PeelInputs {
  /** The target holding the opaque image; the see-through layers go over it. */
  target: GPUTextureView;
  /** The opaque pass's depth (TEXTURE_BINDING usage). */
  opaqueDepth: GPUTextureView;
  width: number;
  height: number;
  /** Bind group 0 of every layer (the frame uniforms). */
  frameBindGroup: GPUBindGroup;
  layers: readonly RenderLayer[];
  /** A pick: called after the first peel with its depth (the nearest see-through fragment per pixel; 1 where none). */
  pick?: (encoder: GPUCommandEncoder, nearest: GPUTextureView) => void;
}

/** Per peel, the samples it drew (occlusion queries), resolved and read back; one frame's in flight. */
interface OcclusionCounts {
  set: GPUQuerySet;
  resolve: GPUBuffer;
  read: GPUBuffer;
  busy: boolean;
}

interface Targets {
  width: number;
  height: number;
  layer: GPUTexture;
  accum: GPUTexture;
  depths: [GPUTexture, GPUTexture];
  layerView: GPUTextureView;
  accumView: GPUTextureView;
  depthViews: [GPUTextureView, GPUTextureView];
  /** Peel k draws into depths[k % 2] and reads depths[(k + 1) % 2] (before peel 0: cleared to 0, nothing peeled). */
  peelGroups: [GPUBindGroup, GPUBindGroup];
  underGroup: GPUBindGroup;
  overGroup: GPUBindGroup;
  opaqueDepth: GPUTextureView;
}

export class DepthPeeler {
  /** Layers peeled per frame at most: surfaces a ray crosses beyond this many are not drawn. */
  layers = 8;
  /**
   * Peel only as deep as the scene needs (the viewer's frames): an occlusion
   * query per peel counts what it drew, read back a frame or two later; the
   * next frames peel one layer past the deepest that drew anything (so a
   * deeper scene is seen and followed), up to `layers`.
   */
  adaptive = false;
  /** Layers the last frame peeled. */
  lastLayers = 0;
  /** Layers the last counted frame drew something in (adaptive). */
  #needed: number | undefined;
  #queries: OcclusionCounts | undefined;
  #targets: Targets | undefined;

  private constructor(
    private readonly device: GPUDevice,
    private readonly under: GPURenderPipeline,
    private readonly over: GPURenderPipeline,
    private readonly textureLayout: GPUBindGroupLayout,
  ) {}

  static async create(device: GPUDevice, targetFormat: GPUTextureFormat): Promise<DepthPeeler> {
    const module = await createShaderModule(device, 'DepthPeeler.shader', [{ name: 'shaders/render/peel.wgsl', code: peelWgsl }]);
    const textureLayout = device.createBindGroupLayout({
      label: 'DepthPeeler.textureLayout',
      entries: [{ binding: 0, visibility: GPUShaderStage.FRAGMENT, texture: { sampleType: 'unfilterable-float' } }],
    });
    const layout = device.createPipelineLayout({ label: 'DepthPeeler', bindGroupLayouts: [textureLayout] });
    const composite = (label: string, format: GPUTextureFormat, blend: GPUBlendComponent) =>
      device.createRenderPipelineAsync({
        label,
        layout,
        vertex: { module, entryPoint: 'vs_fullscreen' },
        fragment: { module, entryPoint: 'fs_composite', targets: [{ format, blend: { color: blend, alpha: blend } }] },
        primitive: { topology: 'triangle-list' },
      });
    const [under, over] = await Promise.all([
      composite('DepthPeeler.under', LAYER_FORMAT, { srcFactor: 'one-minus-dst-alpha', dstFactor: 'one', operation: 'add' }),
      composite('DepthPeeler.over', targetFormat, { srcFactor: 'one', dstFactor: 'one-minus-src-alpha', operation: 'add' }),
    ]);
    return new DepthPeeler(device, under, over, textureLayout);
  }

  /** Whether any layer has see-through content this frame. */
  static anyTransparent(layers: readonly RenderLayer[]): boolean {
    return layers.some((l) => l.transparent === true && l.drawPeel !== undefined);
  }

  #ensureTargets(width: number, height: number, opaqueDepth: GPUTextureView): Targets {
    const t = this.#targets;
    if (t && t.width === width && t.height === height && t.opaqueDepth === opaqueDepth) return t;
    this.#destroyTargets();
    const { device } = this;
    const colour = (label: string) =>
      device.createTexture({
        label,
        size: [width, height],
        format: LAYER_FORMAT,
        usage: GPUTextureUsage.RENDER_ATTACHMENT | GPUTextureUsage.TEXTURE_BINDING,
      });
    const depth = (label: string) =>
      device.createTexture({
        label,
        size: [width, height],
        format: PEEL_DEPTH_FORMAT,
        usage: GPUTextureUsage.RENDER_ATTACHMENT | GPUTextureUsage.TEXTURE_BINDING,
      });
    const layer = colour('DepthPeeler.layer');
    const accum = colour('DepthPeeler.accum');
    const depths: [GPUTexture, GPUTexture] = [depth('DepthPeeler.depth0'), depth('DepthPeeler.depth1')];
    const peelLayout = peelBindGroupLayout(device);
    const peelGroup = (k: number) =>
      device.createBindGroup({
        label: `DepthPeeler.peel${k}`,
        layout: peelLayout,
        entries: [
          { binding: 0, resource: depths[(k + 1) % 2].createView() },
          { binding: 1, resource: opaqueDepth },
        ],
      });
    const textureGroup = (label: string, texture: GPUTexture) =>
      device.createBindGroup({ label, layout: this.textureLayout, entries: [{ binding: 0, resource: texture.createView() }] });
    this.#targets = {
      width,
      height,
      layer,
      accum,
      depths,
      layerView: layer.createView(),
      accumView: accum.createView(),
      depthViews: [depths[0].createView(), depths[1].createView()],
      peelGroups: [peelGroup(0), peelGroup(1)],
      underGroup: textureGroup('DepthPeeler.under', layer),
      overGroup: textureGroup('DepthPeeler.over', accum),
      opaqueDepth,
    };
    return this.#targets;
  }

  /** Peels the see-through layers and composites them over `target`. */
  encode(encoder: GPUCommandEncoder, inputs: PeelInputs): void {
    const t = this.#ensureTargets(inputs.width, inputs.height, inputs.opaqueDepth);
    const clear = { r: 0, g: 0, b: 0, a: 0 };
    // nothing accumulated; "peeled before the first peel" at depth 0 (nothing is in front of the near plane)
    encoder
      .beginRenderPass({
        label: 'DepthPeeler.clear',
        colorAttachments: [{ view: t.accumView, clearValue: clear, loadOp: 'clear', storeOp: 'store' }],
        depthStencilAttachment: { view: t.depthViews[1], depthClearValue: 0, depthLoadOp: 'clear', depthStoreOp: 'store' },
      })
      .end();
    const count = this.adaptive && this.#needed !== undefined ? Math.min(this.layers, this.#needed + 1) : this.layers;
    this.lastLayers = count;
    const queries = this.adaptive ? this.#queryBuffers() : undefined;
    const counting = queries !== undefined && !queries.busy;
    for (let k = 0; k < count; k++) {
      const peel = encoder.beginRenderPass({
        label: `DepthPeeler.peel${k}`,
        colorAttachments: [{ view: t.layerView, clearValue: clear, loadOp: 'clear', storeOp: 'store' }],
        depthStencilAttachment: { view: t.depthViews[k % 2], depthClearValue: 1, depthLoadOp: 'clear', depthStoreOp: 'store' },
        ...(counting ? { occlusionQuerySet: queries.set } : {}),
      });
      peel.setBindGroup(0, inputs.frameBindGroup);
      peel.setBindGroup(2, t.peelGroups[k % 2]);
      if (counting) peel.beginOcclusionQuery(k);
      for (const layer of inputs.layers) if (layer.transparent) layer.drawPeel?.(peel);
      if (counting) peel.endOcclusionQuery();
      peel.end();
      if (k === 0) inputs.pick?.(encoder, t.depthViews[0]);
      const under = encoder.beginRenderPass({
        label: `DepthPeeler.under${k}`,
        colorAttachments: [{ view: t.accumView, loadOp: 'load', storeOp: 'store' }],
      });
      under.setPipeline(this.under);
      under.setBindGroup(0, t.underGroup);
      under.draw(3);
      under.end();
    }
    const over = encoder.beginRenderPass({
      label: 'DepthPeeler.over',
      colorAttachments: [{ view: inputs.target, loadOp: 'load', storeOp: 'store' }],
    });
    over.setPipeline(this.over);
    over.setBindGroup(0, t.overGroup);
    over.draw(3);
    over.end();
    if (counting) {
      encoder.resolveQuerySet(queries.set, 0, count, queries.resolve, 0);
      encoder.copyBufferToBuffer(queries.resolve, 0, queries.read, 0, 8 * count);
      queries.busy = true;
      // read once the frame is submitted (the caller submits this encoder in this task)
      queueMicrotask(() => this.#readCounts(queries, count));
    }
  }

  /** The occlusion query set and its buffers (one frame's counts in flight at a time). */
  #queryBuffers(): OcclusionCounts {
    if (!this.#queries || this.#queries.set.count < this.layers) {
      this.#destroyQueries();
      const { device } = this;
      this.#queries = {
        set: device.createQuerySet({ label: 'DepthPeeler.occlusion', type: 'occlusion', count: this.layers }),
        resolve: device.createBuffer({
          label: 'DepthPeeler.counts',
          size: 8 * this.layers,
          usage: GPUBufferUsage.QUERY_RESOLVE | GPUBufferUsage.COPY_SRC,
        }),
        read: device.createBuffer({
          label: 'DepthPeeler.countsRead',
          size: 8 * this.layers,
          usage: GPUBufferUsage.COPY_DST | GPUBufferUsage.MAP_READ,
        }),
        busy: false,
      };
    }
    return this.#queries;
  }

  #readCounts(q: OcclusionCounts, count: number): void {
    q.read.mapAsync(GPUMapMode.READ, 0, 8 * count).then(
      () => {
        const samples = new BigUint64Array(q.read.getMappedRange(0, 8 * count));
        let deepest = 0;
        for (let k = 0; k < count; k++) if (samples[k] > 0n) deepest = k + 1;
        q.read.unmap();
        q.busy = false;
        this.#needed = deepest;
      },
      () => {
        q.busy = false; // destroyed meanwhile: peel every layer
        this.#needed = undefined;
      },
    );
  }

  #destroyQueries(): void {
    this.#queries?.set.destroy();
    this.#queries?.resolve.destroy();
    this.#queries?.read.destroy();
    this.#queries = undefined;
  }

  #destroyTargets(): void {
    const t = this.#targets;
    if (!t) return;
    t.layer.destroy();
    t.accum.destroy();
    for (const d of t.depths) d.destroy();
    this.#targets = undefined;
  }

  destroy(): void {
    this.#destroyTargets();
    this.#destroyQueries();
  }
}
