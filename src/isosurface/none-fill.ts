// Words [begin, end) of a buffer set to NONE on the GPU (fill_none in
// lru.wgsl): how the block cache empties itself and the slots a growth adds.
// Made once per cache with its pipeline, its parameters (FILL_SLOTS ranges
// per submission, each at a dynamic offset) and one bind group per target.
import { BindGroupCache } from '../gpu/bind-group-cache.ts';
import { dispatchWorkgroups } from '../gpu/dispatch.ts';
import { bindGroupLayout, createComputePipeline } from '../gpu/pipeline-cache.ts';
import { isosurfaceWgsl } from './wgsl.ts';

/** Ranges one submission may fill. */
const FILL_SLOTS = 8;
/** Bytes between two ranges' parameters (the dynamic-offset alignment). */
const FILL_STRIDE = 256;

export class NoneFill {
  readonly #params: GPUBuffer;
  readonly #groups = new BindGroupCache();
  #recorded = 0;

  private constructor(
    private readonly device: GPUDevice,
    private readonly pipeline: GPUComputePipeline,
    private readonly layout: GPUBindGroupLayout,
    private readonly maxWorkgroupsPerDimension: number,
  ) {
    this.#params = device.createBuffer({
      label: 'Isosurface.fillParams',
      size: FILL_SLOTS * FILL_STRIDE,
      usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
    });
  }

  static async create(device: GPUDevice, maxWorkgroupsPerDimension: number): Promise<NoneFill> {
    const layout = bindGroupLayout(device, 'Isosurface.fillNone.layout', [
      { binding: 0, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'uniform', hasDynamicOffset: true, minBindingSize: 8 } },
      { binding: 1, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'storage' } },
    ]);
    const pipeline = await createComputePipeline(device, 'Isosurface.fillNone', isosurfaceWgsl.lru, 'fill_none', {
      layout: [layout],
      constants: { MAX_WG_PER_DIM: maxWorkgroupsPerDimension },
    });
    return new NoneFill(device, pipeline, layout, maxWorkgroupsPerDimension);
  }

  /** Bytes held (the parameters). */
  get byteSize(): number {
    return this.#params.size;
  }

  /** Records words [begin, end) of `target` := NONE. At most FILL_SLOTS per submission (submitted() after it). */
  encode(encoder: GPUCommandEncoder, target: GPUBuffer, begin: number, end: number): void {
    if (end <= begin) return;
    if (this.#recorded >= FILL_SLOTS) throw new Error('BlockCache: too many fills in one submission');
    const offset = this.#recorded++ * FILL_STRIDE;
    this.device.queue.writeBuffer(this.#params, offset, new Uint32Array([begin, end]));
    const pass = encoder.beginComputePass({ label: 'Isosurface.fillNone' });
    pass.setPipeline(this.pipeline);
    const group = this.#groups.key(target).get(() =>
      this.device.createBindGroup({
        label: 'Isosurface.fillNone.bindGroup',
        layout: this.layout,
        entries: [
          { binding: 0, resource: { buffer: this.#params, size: 8 } },
          { binding: 1, resource: { buffer: target } },
        ],
      }),
    );
    pass.setBindGroup(0, group, [offset]);
    dispatchWorkgroups(pass, Math.ceil((end - begin) / 64), this.maxWorkgroupsPerDimension);
    pass.end();
  }

  /** The fills recorded so far were submitted: the parameters can be written again. */
  submitted(): void {
    this.#recorded = 0;
  }

  destroy(): void {
    this.#params.destroy();
  }
}
