// Depth of the opaque layers (neuron traces, the isosurface) in a
// texture of its own, drawn before the frame's main pass, so the volume
// renderer can stop its rays where they meet opaque geometry. The viewer's
// own depth buffer cannot be sampled while it is the pass's attachment.
import { DEPTH_FORMAT, type Viewer } from '../../render/viewer.ts';

export interface DepthDrawer {
  /**
   * Records depth-only draws (pipelines with no colour target) into `pass`.
   * The pre-pass records in the first before-frame hook, so what a drawer
   * draws must be set before the frame, not in a later hook.
   */
  drawDepth(pass: GPURenderPassEncoder): void;
  /** Whether there is anything to draw. */
  readonly hasDepth: boolean;
}

export class DepthPrepass {
  private texture: GPUTexture | undefined;
  private textureView: GPUTextureView | undefined;
  /** Reused every frame (the view changes only on resize): the render loop allocates no descriptors. */
  private readonly depthAttachment: GPURenderPassDepthStencilAttachment = {
    view: undefined as unknown as GPUTextureView,
    depthClearValue: 1,
    depthLoadOp: 'clear',
    depthStoreOp: 'store',
  };
  private readonly passDescriptor: GPURenderPassDescriptor = {
    label: 'DepthPrepass.pass',
    colorAttachments: [],
    depthStencilAttachment: this.depthAttachment,
  };
  private readonly drawers: DepthDrawer[] = [];
  private readonly listeners: (() => void)[] = [];
  private readonly removeHook: () => void;

  constructor(private readonly viewer: Viewer) {
    this.removeHook = viewer.addBeforeFrame((encoder) => this.record(encoder));
    this.ensureTexture();
  }

  add(drawer: DepthDrawer): void {
    this.drawers.push(drawer);
  }

  /** True when some layer writes depth this frame. */
  get active(): boolean {
    return this.drawers.some((d) => d.hasDepth);
  }

  /** Called whenever the texture is re-created (bind groups that sample it must be rebuilt). */
  onResize(listener: () => void): void {
    this.listeners.push(listener);
  }

  get view(): GPUTextureView {
    this.ensureTexture();
    return this.textureView!;
  }

  private ensureTexture(): GPUTexture {
    const { width, height } = this.viewer.canvas;
    if (!this.texture || this.texture.width !== width || this.texture.height !== height) {
      this.texture?.destroy();
      this.texture = this.viewer.device.createTexture({
        label: 'DepthPrepass.depth',
        size: [width, height],
        format: DEPTH_FORMAT,
        usage: GPUTextureUsage.RENDER_ATTACHMENT | GPUTextureUsage.TEXTURE_BINDING,
      });
      this.textureView = this.texture.createView();
      for (const l of this.listeners) l();
    }
    return this.texture;
  }

  private record(encoder: GPUCommandEncoder): void {
    this.ensureTexture();
    this.depthAttachment.view = this.textureView!;
    const pass = encoder.beginRenderPass(this.passDescriptor);
    pass.setBindGroup(0, this.viewer.frameBindGroup);
    for (const d of this.drawers) if (d.hasDepth) d.drawDepth(pass);
    pass.end();
  }

  destroy(): void {
    this.removeHook();
    this.texture?.destroy();
  }
}
