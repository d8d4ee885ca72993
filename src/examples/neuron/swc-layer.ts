// Neuron traces from SWC files (shaders/volume/swc.wgsl): every segment from
// a sample to its parent as a line or a shaded tube with round joints,
// coloured by SWC type or by file, in the volume's world space. Also draws
// its depth for the volume renderer's pre-pass.
import swcWgsl from '../../../shaders/volume/swc.wgsl?raw';
import { createShaderModule } from '../../gpu/wgsl.ts';
import type { Bounds } from '../../render/camera.ts';
import { DEPTH_FORMAT, frameSnippet, type RenderLayer, type Viewer } from '../../render/viewer.ts';
import { swcTypeColor, type SwcTree } from '../../loaders/swc.ts';
import type { DepthDrawer } from './depth-prepass.ts';

export type Vec3 = [number, number, number];
export type TraceStyle = 'tubes' | 'lines';
export type TraceColoring = 'type' | 'file';

export interface Trace {
  tree: SwcTree;
  /** Colour when colouring by file. */
  color: Vec3;
  visible: boolean;
}

/** Distinct colours for traces compared side by side. */
export const FILE_COLORS: Vec3[] = [
  [1.0, 0.42, 0.3],
  [0.35, 0.75, 1.0],
  [1.0, 0.85, 0.25],
  [0.75, 0.45, 1.0],
  [0.35, 0.95, 0.55],
  [1.0, 0.5, 0.8],
];

const SEGMENT_FLOATS = 12;

export class SwcLayer implements RenderLayer, DepthDrawer {
  private readonly uniforms: GPUBuffer;
  /** Written every frame (made once: the render loop allocates nothing). */
  private readonly uniformData = new Float32Array(4);
  private segments: GPUBuffer | undefined;
  private bindGroup: GPUBindGroup | undefined;
  private count = 0;
  private traces: Trace[] = [];
  private box: Bounds | undefined;
  style: TraceStyle = 'tubes';
  coloring: TraceColoring = 'type';
  /** Thinnest tube on screen, in device pixels. */
  minPx = 2;
  /** Multiplies the SWC radii (1 = as traced). */
  radiusScale = 1;
  /** Maps SWC coordinates to world (e.g. voxel units to microns). */
  coordinateScale: Vec3 = [1, 1, 1];
  visible = true;

  private constructor(
    private readonly viewer: Viewer,
    private readonly layout: GPUBindGroupLayout,
    private readonly pipelines: Record<'line' | 'tube' | 'joint' | 'lineDepth' | 'tubeDepth' | 'jointDepth', GPURenderPipeline>,
  ) {
    this.uniforms = viewer.device.createBuffer({
      label: 'SwcLayer.uniforms',
      size: 16,
      usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
    });
    viewer.addBeforeFrame(() => this.writeUniforms());
  }

  static async create(viewer: Viewer): Promise<SwcLayer> {
    const { device } = viewer;
    const module = await createShaderModule(device, 'SwcLayer.shader', [frameSnippet, { name: 'shaders/volume/swc.wgsl', code: swcWgsl }]);
    const layout = device.createBindGroupLayout({
      label: 'SwcLayer.layout',
      entries: [
        { binding: 0, visibility: GPUShaderStage.VERTEX, buffer: { type: 'uniform' } },
        { binding: 1, visibility: GPUShaderStage.VERTEX, buffer: { type: 'read-only-storage' } },
      ],
    });
    const pipelineLayout = device.createPipelineLayout({ bindGroupLayouts: [viewer.frameBindGroupLayout, layout] });
    const make = (label: string, vs: string, fs: string | undefined, topology: GPUPrimitiveTopology) =>
      device.createRenderPipelineAsync({
        label: `SwcLayer.${label}`,
        layout: pipelineLayout,
        vertex: { module, entryPoint: vs },
        fragment:
          fs === undefined
            ? undefined
            : fs.endsWith('_depth')
              ? { module, entryPoint: fs, targets: [] }
              : { module, entryPoint: fs, targets: [{ format: viewer.format }] },
        primitive: { topology },
        depthStencil: { format: DEPTH_FORMAT, depthWriteEnabled: true, depthCompare: 'less-equal' },
      });
    const [line, tube, joint, lineDepth, tubeDepth, jointDepth] = await Promise.all([
      make('line', 'vs_line', 'fs_line', 'line-list'),
      make('tube', 'vs_tube', 'fs_tube', 'triangle-list'),
      make('joint', 'vs_joint', 'fs_joint', 'triangle-list'),
      make('lineDepth', 'vs_line', undefined, 'line-list'),
      make('tubeDepth', 'vs_tube', undefined, 'triangle-list'),
      make('jointDepth', 'vs_joint', 'fs_joint_depth', 'triangle-list'),
    ]);
    return new SwcLayer(viewer, layout, { line, tube, joint, lineDepth, tubeDepth, jointDepth });
  }

  get hasDepth(): boolean {
    return this.visible && this.count > 0;
  }

  /** World bounds of the visible traces (with radii), or undefined when there are none. */
  get bounds(): Bounds | undefined {
    return this.box;
  }

  get segmentCount(): number {
    return this.count;
  }

  setTraces(traces: Trace[]): void {
    this.traces = traces;
    this.rebuild();
  }

  /** Re-creates the segment buffer (after changes of traces, colouring or scale). */
  rebuild(): void {
    const { device } = this.viewer;
    let n = 0;
    for (const t of this.traces) if (t.visible) n += t.tree.count;
    const data = new Float32Array(Math.max(1, n) * SEGMENT_FLOATS);
    const min: Vec3 = [Infinity, Infinity, Infinity];
    const max: Vec3 = [-Infinity, -Infinity, -Infinity];
    const s = this.coordinateScale;
    let k = 0;
    for (const t of this.traces) {
      if (!t.visible) continue;
      const { positions: p, radii, parentIndex, types } = t.tree;
      for (let i = 0; i < t.tree.count; i++) {
        // Every sample is the child end "a" of one segment; roots get a zero-length one (a joint).
        const j = parentIndex[i] >= 0 ? parentIndex[i] : i;
        const color = this.coloring === 'file' ? t.color : swcTypeColor(types[i]);
        // Traces often mark terminal radii as 0: keep them visible.
        const ra = Math.max(radii[i], 0);
        const rb = Math.max(radii[j], 0);
        const o = k * SEGMENT_FLOATS;
        data[o] = p[3 * i] * s[0];
        data[o + 1] = p[3 * i + 1] * s[1];
        data[o + 2] = p[3 * i + 2] * s[2];
        data[o + 3] = ra;
        data[o + 4] = p[3 * j] * s[0];
        data[o + 5] = p[3 * j + 1] * s[1];
        data[o + 6] = p[3 * j + 2] * s[2];
        data[o + 7] = rb;
        data[o + 8] = color[0];
        data[o + 9] = color[1];
        data[o + 10] = color[2];
        data[o + 11] = 1;
        for (let a = 0; a < 3; a++) {
          const v = data[o + a];
          min[a] = Math.min(min[a], v - ra);
          max[a] = Math.max(max[a], v + ra);
        }
        k++;
      }
    }
    this.count = k;
    this.box = k > 0 ? { min, max } : undefined;
    if (!this.segments || this.segments.size < data.byteLength) {
      this.segments?.destroy();
      this.segments = device.createBuffer({
        label: 'SwcLayer.segments',
        size: data.byteLength,
        usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST,
      });
      this.bindGroup = device.createBindGroup({
        label: 'SwcLayer.bindGroup',
        layout: this.layout,
        entries: [
          { binding: 0, resource: { buffer: this.uniforms } },
          { binding: 1, resource: { buffer: this.segments } },
        ],
      });
    }
    device.queue.writeBuffer(this.segments, 0, data);
    this.viewer.requestFrame();
  }

  private writeUniforms(): void {
    const cam = this.viewer.camera;
    const focal = this.viewer.canvas.height / 2 / Math.tan(cam.fovY / 2);
    const u = this.uniformData;
    u[0] = focal;
    u[1] = this.minPx;
    u[2] = this.radiusScale;
    u[3] = 0;
    this.viewer.device.queue.writeBuffer(this.uniforms, 0, u);
  }

  private drawWith(pass: GPURenderPassEncoder, line: GPURenderPipeline, tube: GPURenderPipeline, joint: GPURenderPipeline): void {
    if (!this.visible || this.count === 0 || !this.bindGroup) return;
    pass.setBindGroup(1, this.bindGroup);
    if (this.style === 'lines') {
      pass.setPipeline(line);
      pass.draw(2, this.count);
    } else {
      pass.setPipeline(tube);
      pass.draw(6, this.count);
      pass.setPipeline(joint);
      pass.draw(6, this.count);
    }
  }

  draw(pass: GPURenderPassEncoder): void {
    const p = this.pipelines;
    this.drawWith(pass, p.line, p.tube, p.joint);
  }

  drawDepth(pass: GPURenderPassEncoder): void {
    const p = this.pipelines;
    this.drawWith(pass, p.lineDepth, p.tubeDepth, p.jointDepth);
  }

  destroy(): void {
    this.segments?.destroy();
    this.uniforms.destroy();
  }
}
