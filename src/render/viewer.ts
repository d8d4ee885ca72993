// A WebGPU canvas with an arcball camera, depth buffer, high-DPI resize and
// an on-demand frame loop. Drawable things implement `RenderLayer`; work that
// must be submitted before a frame (compute) goes in `beforeFrame` hooks.

import { mat4, vec3, vec4 } from 'gl-matrix';
import frameWgsl from '../../shaders/render/frame.wgsl?raw';
import { GpuTimer, type SubmissionTiming } from '../gpu/timing.ts';
import type { WgslPart } from '../gpu/wgsl.ts';
import { ArcballCamera, type Bounds, type UpAxis } from './camera.ts';
import { CameraControls, type CameraControlsOptions } from './camera-controls.ts';
import { DepthPeeler, PEEL_DEPTH_FORMAT } from './depth-peel.ts';
import type { RenderLayer } from './layer.ts';
import { DepthProbe } from './depth-probe.ts';

export const frameSnippet: WgslPart = { name: 'shaders/render/frame.wgsl', code: frameWgsl };

export const DEPTH_FORMAT: GPUTextureFormat = PEEL_DEPTH_FORMAT;
export const FRAME_UNIFORM_BYTES = 4 * (16 + 16 + 4 + 4 + 4);

/** Bind group 0 of every layer's pipeline: the frame uniforms (shaders/render/frame.wgsl). */
export function createFrameBindGroupLayout(device: GPUDevice, label = 'Viewer.frameLayout'): GPUBindGroupLayout {
  return device.createBindGroupLayout({
    label,
    entries: [{ binding: 0, visibility: GPUShaderStage.VERTEX | GPUShaderStage.FRAGMENT, buffer: { type: 'uniform' } }],
  });
}

const frameScratch = { viewProj: mat4.create(), view: mat4.create(), eye: vec3.create(), toLight: vec3.create() };

/** The frame uniforms for `camera` on a width x height target (camera.aspect is set from them). Allocates nothing given `out`. */
export function frameUniformData(
  camera: ArcballCamera,
  width: number,
  height: number,
  out = new Float32Array(FRAME_UNIFORM_BYTES / 4),
): Float32Array {
  const t = frameScratch;
  camera.aspect = width / height;
  out.set(camera.viewProjection(t.viewProj) as Float32Array, 0);
  out.set(camera.view(t.view) as Float32Array, 16);
  const eye = camera.eyePosition(t.eye);
  out[32] = eye[0];
  out[33] = eye[1];
  out[34] = eye[2];
  out[35] = 1;
  // Headlight: toward the eye.
  const toLight = vec3.sub(t.toLight, eye, camera.target);
  vec3.normalize(toLight, toLight);
  out[36] = toLight[0];
  out[37] = toLight[1];
  out[38] = toLight[2];
  out[39] = 0;
  out[40] = width;
  out[41] = height;
  out[42] = 1 / width;
  out[43] = 1 / height;
  return out;
}

/** What a pick found: the world point under the pixel and its depth (0 near .. 1 far). */
export interface PickHit {
  world: [number, number, number];
  depth: number;
}

/** NDC (x, y in -1..1, z the depth in 0..1) -> world, through the inverse of `viewProj`. */
export function unproject(viewProj: mat4, ndc: readonly number[]): [number, number, number] {
  const inv = mat4.create();
  if (!mat4.invert(inv, viewProj)) return [Number.NaN, Number.NaN, Number.NaN];
  const p = vec4.transformMat4(vec4.create(), vec4.fromValues(ndc[0], ndc[1], ndc[2], 1), inv);
  return [p[0] / p[3], p[1] / p[3], p[2] / p[3]];
}

export type { RenderLayer };

export interface ViewerOptions {
  clearColor?: GPUColor;
  /** Called after every camera change (e.g. to store the view in the URL). */
  onCameraChange?: () => void;
  /** The camera to drive (default: a new one); a viewer made again on a new device keeps the old one's. */
  camera?: ArcballCamera;
  /** A left click that did not drag (CameraControls.onClick). */
  onClick?: (u: number, v: number) => void;
  /** Drags the owner takes (handles, Ctrl-drags: CameraControls.grab) and the pointer's hover. */
  grab?: Pick<CameraControlsOptions, 'grab' | 'grabMove' | 'grabEnd' | 'hover'>;
}

export class Viewer {
  readonly camera: ArcballCamera;
  readonly controls: CameraControls;
  readonly format: GPUTextureFormat;
  readonly frameBindGroupLayout: GPUBindGroupLayout;
  readonly frameBindGroup: GPUBindGroup;
  clearColor: GPUColor;
  /** Frames per second over the last second of continuous drawing. */
  fps = 0;
  /** Frames drawn since creation (tests wait on this). */
  framesDrawn = 0;

  private readonly context: GPUCanvasContext;
  private readonly frameUniforms: GPUBuffer;
  private depth: GPUTexture | undefined;
  private depthView: GPUTextureView | undefined;
  /** Reused every frame (only the colour view changes): the frame loop allocates no descriptors. */
  private readonly colorAttachment: GPURenderPassColorAttachment;
  private readonly depthAttachment: GPURenderPassDepthStencilAttachment;
  private readonly passDescriptor: GPURenderPassDescriptor;
  private readonly encoderDescriptor: GPUCommandEncoderDescriptor = { label: 'Viewer.frame' };
  private readonly submitList: GPUCommandBuffer[] = [];
  private readonly layers: RenderLayer[] = [];
  /** Drawn over the finished scene (see-through layers included) in a pass without depth: handles. */
  private readonly overlays: RenderLayer[] = [];
  private readonly overlayAttachment: GPURenderPassColorAttachment;
  private readonly overlayDescriptor: GPURenderPassDescriptor;
  private withoutOverlays = false;
  private readonly beforeFrame: ((encoder: GPUCommandEncoder) => void)[] = [];
  private frameRequested = false;
  private readonly onAnimationFrame = (t: number): void => this.frame(t);
  private readonly resizeObserver: ResizeObserver;
  private fpsWindow: number[] = [];
  private readonly scratch = new Float32Array(FRAME_UNIFORM_BYTES / 4);
  private destroyed = false;
  private bounds: Bounds | undefined;
  /** Reads a depth texel for pick() (made by the first pick). */
  private depthProbe: DepthProbe | undefined;
  /** A pick waiting for the next frame (pick()). */
  private pendingPick: { x: number; y: number; resolve: (p: PickHit | null) => void; reject: (e: Error) => void } | undefined;
  /** Waiting for the next frame's time (timeNextFrame). */
  private frameTimings: { resolve: (t: SubmissionTiming) => void; reject: (e: Error) => void }[] = [];
  /** Times frames that are asked for (made by the first). */
  private frameTimer: GpuTimer | undefined;
  /** Made when a see-through layer first appears. */
  private peeler: DepthPeeler | undefined;
  private peelerMaking = false;

  constructor(
    readonly device: GPUDevice,
    readonly canvas: HTMLCanvasElement,
    options: ViewerOptions = {},
  ) {
    this.camera = options.camera ?? new ArcballCamera();
    const context = canvas.getContext('webgpu');
    if (!context) throw new Error('Could not get a WebGPU context for the canvas.');
    this.context = context;
    this.format = navigator.gpu.getPreferredCanvasFormat();
    context.configure({ device, format: this.format, alphaMode: 'opaque' });
    this.clearColor = options.clearColor ?? { r: 0.09, g: 0.1, b: 0.12, a: 1 };
    this.colorAttachment = { view: undefined as unknown as GPUTextureView, clearValue: this.clearColor, loadOp: 'clear', storeOp: 'store' };
    this.depthAttachment = {
      view: undefined as unknown as GPUTextureView,
      depthClearValue: 1,
      depthLoadOp: 'clear',
      depthStoreOp: 'store',
    };
    this.passDescriptor = { label: 'Viewer.pass', colorAttachments: [this.colorAttachment], depthStencilAttachment: this.depthAttachment };
    this.overlayAttachment = { view: undefined as unknown as GPUTextureView, loadOp: 'load', storeOp: 'store' };
    this.overlayDescriptor = { label: 'Viewer.overlayPass', colorAttachments: [this.overlayAttachment] };

    this.frameUniforms = device.createBuffer({
      label: 'Viewer.frameUniforms',
      size: FRAME_UNIFORM_BYTES,
      usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
    });
    this.frameBindGroupLayout = createFrameBindGroupLayout(device);
    this.frameBindGroup = device.createBindGroup({
      label: 'Viewer.frameBindGroup',
      layout: this.frameBindGroupLayout,
      entries: [{ binding: 0, resource: { buffer: this.frameUniforms } }],
    });

    this.controls = new CameraControls(canvas, this.camera, {
      onChange: () => {
        this.requestFrame();
        options.onCameraChange?.();
      },
      onFit: () => this.fitView(),
      onClick: options.onClick,
      ...options.grab,
    });

    this.resizeObserver = new ResizeObserver((entries) => {
      for (const entry of entries) {
        const box = entry.devicePixelContentBoxSize?.[0];
        const w = box ? box.inlineSize : Math.round(entry.contentRect.width * devicePixelRatio);
        const h = box ? box.blockSize : Math.round(entry.contentRect.height * devicePixelRatio);
        const max = device.limits.maxTextureDimension2D;
        canvas.width = Math.max(1, Math.min(w, max));
        canvas.height = Math.max(1, Math.min(h, max));
      }
      this.requestFrame();
    });
    try {
      this.resizeObserver.observe(canvas, { box: 'device-pixel-content-box' });
    } catch {
      this.resizeObserver.observe(canvas);
    }
  }

  addLayer(layer: RenderLayer): void {
    this.layers.push(layer);
    this.requestFrame();
  }

  removeLayer(layer: RenderLayer): void {
    const i = this.layers.indexOf(layer);
    if (i >= 0) this.layers.splice(i, 1);
    this.requestFrame();
  }

  /** A layer drawn over everything else, without depth (its pipeline has no depth-stencil state). */
  addOverlay(layer: RenderLayer): void {
    if (!this.overlays.includes(layer)) this.overlays.push(layer);
    this.requestFrame();
  }

  removeOverlay(layer: RenderLayer): void {
    const i = this.overlays.indexOf(layer);
    if (i >= 0) this.overlays.splice(i, 1);
    this.requestFrame();
  }

  /** Runs `hook` at the start of each frame's command encoder. */
  addBeforeFrame(hook: (encoder: GPUCommandEncoder) => void): () => void {
    this.beforeFrame.push(hook);
    return () => {
      const i = this.beforeFrame.indexOf(hook);
      if (i >= 0) this.beforeFrame.splice(i, 1);
    };
  }

  /** The axis fitTo() shows pointing up (reset view). */
  upAxis: UpAxis = 'z';

  fitTo(bounds: Bounds): void {
    this.bounds = bounds;
    this.camera.fit(bounds, this.upAxis);
    this.requestFrame();
  }

  /** Changes the up axis and fits the view (a new reset view) to the last bounds. */
  setUpAxis(up: UpAxis): void {
    this.upAxis = up;
    if (this.bounds) this.fitTo(this.bounds);
  }

  /** Shows the bounds given to fitTo whole again, keeping the view direction (F). */
  fitView(): void {
    if (this.bounds) this.camera.frameBounds(this.bounds);
    else this.camera.reset();
    this.requestFrame();
  }

  requestFrame(): void {
    if (this.frameRequested || this.destroyed) return;
    this.frameRequested = true;
    requestAnimationFrame(this.onAnimationFrame);
  }

  /**
   * Draws a frame at once (not at the next animation frame): read the canvas
   * right after it in the same task, e.g. for a screenshot (without the
   * overlays: handles are not part of the picture).
   */
  drawNow(): void {
    if (this.destroyed) return;
    this.withoutOverlays = true;
    this.frame(performance.now());
    this.withoutOverlays = false;
    if (this.overlays.length > 0) this.requestFrame();
  }

  private ensureDepthView(): GPUTextureView {
    const { width, height } = this.canvas;
    if (!this.depth || !this.depthView || this.depth.width !== width || this.depth.height !== height) {
      this.depth?.destroy();
      this.depth = this.device.createTexture({
        label: 'Viewer.depth',
        size: [width, height],
        format: DEPTH_FORMAT,
        // read by the depth peeling of see-through layers
        usage: GPUTextureUsage.RENDER_ATTACHMENT | GPUTextureUsage.TEXTURE_BINDING,
      });
      this.depthView = this.depth.createView();
    }
    return this.depthView;
  }

  private writeFrameUniforms(): void {
    const u = frameUniformData(this.camera, this.canvas.width, this.canvas.height, this.scratch);
    this.device.queue.writeBuffer(this.frameUniforms, 0, u as Float32Array<ArrayBuffer>);
  }

  /**
   * The time of the next frame, once drawn (a frame is requested): its main
   * pass (every opaque layer, rays included) by GPU timestamps where the
   * device has them, else the queue's wall time from the frame's submission
   * to done (the whole frame). The benchmark's time per image.
   */
  timeNextFrame(): Promise<SubmissionTiming> {
    if (this.destroyed) return Promise.reject(new Error('the viewer is gone'));
    return new Promise((resolve, reject) => {
      this.frameTimings.push({ resolve, reject });
      this.requestFrame();
    });
  }

  private frame(time: number): void {
    this.frameRequested = false;
    if (this.destroyed) return;
    const waiting = this.frameTimings.splice(0);
    const timing = waiting.length > 0 ? (this.frameTimer ??= new GpuTimer(this.device, 1)).begin() : undefined;
    this.fpsWindow.push(time);
    while (this.fpsWindow.length > 0 && time - this.fpsWindow[0] > 1000) this.fpsWindow.shift();
    this.fps = this.fpsWindow.length > 1 ? ((this.fpsWindow.length - 1) * 1000) / (time - this.fpsWindow[0]) : 0;

    this.writeFrameUniforms();
    const encoder = this.device.createCommandEncoder(this.encoderDescriptor);
    for (const hook of this.beforeFrame) hook(encoder);
    const target = this.context.getCurrentTexture().createView();
    this.colorAttachment.view = target;
    this.colorAttachment.clearValue = this.clearColor;
    const depthView = this.ensureDepthView();
    this.depthAttachment.view = depthView;
    const timestampWrites = timing?.renderPass('frame');
    if (timestampWrites) this.passDescriptor.timestampWrites = timestampWrites;
    const pass = encoder.beginRenderPass(this.passDescriptor);
    delete this.passDescriptor.timestampWrites;
    pass.setBindGroup(0, this.frameBindGroup);
    for (const layer of this.layers) layer.draw(pass);
    pass.end();
    // a pick waits for the frame that draws every layer: see-through ones need the peeler, made on first use
    const peelerPending = !this.peeler && DepthPeeler.anyTransparent(this.layers);
    const pick = peelerPending ? undefined : this.pendingPick;
    if (pick) this.pendingPick = undefined;
    // a pick reads the opaque depth (f32 0) and the nearest see-through one (f32 1: 1 unless peeled)
    const probe = this.depthProbe;
    const pickRead = pick && probe ? this.#pickBuffers() : undefined;
    const probeUniforms: GPUBuffer[] = [];
    if (pick && probe && pickRead) {
      this.device.queue.writeBuffer(pickRead.values, 0, Float32Array.of(1, 1));
      probeUniforms.push(probe.encode(encoder, depthView, pick.x, pick.y, pickRead.values, 0));
    }
    if (DepthPeeler.anyTransparent(this.layers)) {
      if (this.peeler) {
        const { width, height } = this.canvas;
        this.peeler.encode(encoder, {
          target,
          opaqueDepth: depthView,
          width,
          height,
          frameBindGroup: this.frameBindGroup,
          layers: this.layers,
          ...(pick && probe && pickRead
            ? {
                pick: (e: GPUCommandEncoder, nearest: GPUTextureView) =>
                  probeUniforms.push(probe.encode(e, nearest, pick.x, pick.y, pickRead.values, 1)),
              }
            : {}),
        });
      } else this.makePeeler();
    }
    if (this.overlays.length > 0 && !this.withoutOverlays) {
      this.overlayAttachment.view = target;
      const over = encoder.beginRenderPass(this.overlayDescriptor);
      over.setBindGroup(0, this.frameBindGroup);
      for (const layer of this.overlays) layer.draw(over);
      over.end();
    }
    timing?.resolve(encoder);
    this.submitList[0] = encoder.finish();
    this.device.queue.submit(this.submitList);
    this.submitList.length = 0;
    this.framesDrawn++;
    if (timing) {
      timing.submitted();
      timing.read().then(
        (t) => {
          for (const w of waiting) w.resolve(t);
        },
        (e: Error) => {
          for (const w of waiting) w.reject(e);
        },
      );
    }
    if (pick && pickRead) {
      for (const u of probeUniforms) u.destroy();
      this.resolvePick(pick, pickRead.values, pickRead.readback);
    } else pick?.resolve(null);
  }

  /**
   * The nearest surface under a point of the canvas (u, v: fractions from its
   * top left), see-through ones included, as drawn by the next frame; null
   * where the ray meets none.
   */
  async pick(u: number, v: number): Promise<PickHit | null> {
    this.depthProbe ??= await DepthProbe.create(this.device);
    const { width, height } = this.canvas;
    const x = Math.min(width - 1, Math.max(0, Math.floor(u * width)));
    const y = Math.min(height - 1, Math.max(0, Math.floor(v * height)));
    this.pendingPick?.resolve(null); // a newer pick replaces one not yet drawn
    return new Promise((resolve, reject) => {
      this.pendingPick = { x, y, resolve, reject };
      this.requestFrame();
    });
  }

  /** The pick's small buffers: the probed depths (STORAGE) and their readback. */
  #pickBuffers(): { values: GPUBuffer; readback: GPUBuffer } {
    return {
      values: this.device.createBuffer({
        label: 'Viewer.pick',
        size: 8,
        usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST,
      }),
      readback: this.device.createBuffer({ label: 'Viewer.pickRead', size: 8, usage: GPUBufferUsage.COPY_DST | GPUBufferUsage.MAP_READ }),
    };
  }

  private resolvePick(pick: NonNullable<Viewer['pendingPick']>, values: GPUBuffer, readback: GPUBuffer): void {
    const { width, height } = this.canvas;
    const viewProj = this.camera.viewProjection(mat4.create());
    const encoder = this.device.createCommandEncoder({ label: 'Viewer.pickRead' });
    encoder.copyBufferToBuffer(values, 0, readback, 0, 8);
    this.device.queue.submit([encoder.finish()]);
    values.destroy();
    readback.mapAsync(GPUMapMode.READ).then(
      () => {
        const f = new Float32Array(readback.getMappedRange());
        const depth = Math.min(f[0], f[1]);
        readback.destroy();
        if (!(depth < 1)) return pick.resolve(null);
        const ndc = [((pick.x + 0.5) / width) * 2 - 1, 1 - ((pick.y + 0.5) / height) * 2, depth];
        pick.resolve({ world: unproject(viewProj, ndc), depth });
      },
      (e: Error) => {
        readback.destroy();
        pick.reject(e);
      },
    );
  }

  /** The depth peeler, made once (the see-through layers appear from the frame after). */
  private makePeeler(): void {
    if (this.peelerMaking) return;
    this.peelerMaking = true;
    void DepthPeeler.create(this.device, this.format).then(
      (p) => {
        if (this.destroyed) return p.destroy();
        p.adaptive = true; // as deep as the scene needs (at most 8)
        this.peeler = p;
        this.requestFrame();
      },
      (e) => {
        this.peelerMaking = false;
        console.error('depth peeling:', e);
        // a pick waiting for the peeler would wait for ever
        this.pendingPick?.reject(e instanceof Error ? e : new Error(String(e)));
        this.pendingPick = undefined;
      },
    );
  }

  destroy(): void {
    this.destroyed = true;
    for (const w of this.frameTimings.splice(0)) w.reject(new Error('the viewer is gone'));
    this.frameTimer?.destroy();
    this.peeler?.destroy();
    this.resizeObserver.disconnect();
    this.controls.dispose();
    this.depth?.destroy();
    this.frameUniforms.destroy();
  }
}
