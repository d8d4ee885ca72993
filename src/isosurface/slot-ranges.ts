// [min, max] per slot of a chunk pool, reduced on the GPU from the blocks'
// ranges (shaders/isosurface/slot_ranges.wgsl): what a stream learns of each
// brick as it arrives (src/store/learnt-ranges.ts), read back as 8 bytes per
// slot instead of 8 per block (32 KiB for a 64^3 chunk). One per surface over
// a pool, made with it; its scratch (slot list, result, staging) grows on
// demand and is kept; reads are served one after the other (one staging).
import { bindGroup, bufferLayout } from '../gpu/bindings.ts';
import { createComputePipeline } from '../gpu/pipeline-cache.ts';
import { isosurfaceWgsl } from './wgsl.ts';

/** Workgroups per dispatch at most (each strides over the slots). */
const MAX_GROUPS = 4096;

interface Scratch {
  slots: number;
  list: GPUBuffer;
  out: GPUBuffer;
  staging: GPUBuffer;
  group: GPUBindGroup;
}

export class SlotRangeReducer {
  #scratch: Scratch | null = null;
  readonly #params: GPUBuffer;
  #queue: Promise<unknown> = Promise.resolve();
  /** Reads started and not ended: none, and a read submits at once. */
  #pending = 0;
  #destroyed = false;

  private constructor(
    private readonly device: GPUDevice,
    private readonly pipeline: GPUComputePipeline,
    private readonly layout: GPUBindGroupLayout,
    /** 2 f32 per block id (ActiveBlocks.blockRanges). */
    private readonly blockRanges: GPUBuffer,
    private readonly blocksPerChunk: number,
  ) {
    this.#params = device.createBuffer({
      label: 'Isosurface.slotRanges.params',
      size: 16,
      usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
    });
  }

  static async create(device: GPUDevice, blockRanges: GPUBuffer, blocksPerChunk: number): Promise<SlotRangeReducer> {
    const layout = bufferLayout(device, 'Isosurface.slotRanges.layout', ['read', 'read', 'uniform', 'rw']);
    const pipeline = await createComputePipeline(device, 'Isosurface.slotRanges', isosurfaceWgsl.slotRanges, 'slot_ranges_of', {
      layout: [layout],
    });
    return new SlotRangeReducer(device, pipeline, layout, blockRanges, blocksPerChunk);
  }

  /** Bytes held (the parameters and the scratch). */
  get byteSize(): number {
    const s = this.#scratch;
    return this.#params.size + (s ? s.list.size + s.out.size + s.staging.size : 0);
  }

  /**
   * [min, max] per listed slot over its blocks' ranges, as of the last
   * ranges computed (the empty range [FLT_MAX, -FLT_MAX] for a slot without
   * a finite value). The reduction and the copy are submitted before this
   * returns (in queue order after work already submitted); the map waits for
   * the GPU.
   */
  read(slots: readonly number[]): Promise<Float32Array> {
    if (slots.length === 0) return Promise.resolve(new Float32Array(0));
    if (this.#destroyed) return Promise.reject(new Error('Isosurface: destroyed'));
    // one staging buffer: a read waits for the one before to be mapped and unmapped (none: submitted now)
    const run = (this.#pending === 0 ? this.#read(slots) : this.#queue.then(() => this.#read(slots))).finally(() => {
      this.#pending--;
    });
    this.#pending++;
    this.#queue = run.catch(() => {});
    return run;
  }

  async #read(slots: readonly number[]): Promise<Float32Array> {
    if (this.#destroyed) throw new Error('Isosurface: destroyed');
    const { device } = this;
    const s = this.#scratchFor(slots.length);
    device.queue.writeBuffer(s.list, 0, new Uint32Array(slots));
    device.queue.writeBuffer(this.#params, 0, new Uint32Array([slots.length, this.blocksPerChunk, 0, 0]));
    const encoder = device.createCommandEncoder({ label: 'Isosurface.slotRanges' });
    const pass = encoder.beginComputePass({ label: 'Isosurface.slotRanges' });
    pass.setPipeline(this.pipeline);
    pass.setBindGroup(0, s.group);
    pass.dispatchWorkgroups(Math.min(slots.length, MAX_GROUPS));
    pass.end();
    encoder.copyBufferToBuffer(s.out, 0, s.staging, 0, slots.length * 8);
    device.queue.submit([encoder.finish()]);
    await s.staging.mapAsync(GPUMapMode.READ, 0, slots.length * 8);
    try {
      return new Float32Array(s.staging.getMappedRange(0, slots.length * 8).slice(0));
    } finally {
      s.staging.unmap();
    }
  }

  /** Scratch for at least `slots` slots (made again, larger, when it must grow). */
  #scratchFor(slots: number): Scratch {
    const s = this.#scratch;
    if (s && s.slots >= slots) return s;
    const { device } = this;
    const n = Math.max(slots, 2 * (s?.slots ?? 0), 64);
    if (s) for (const b of [s.list, s.out, s.staging]) b.destroy();
    const list = device.createBuffer({
      label: 'Isosurface.slotRanges.list',
      size: 4 * n,
      usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST,
    });
    const out = device.createBuffer({
      label: 'Isosurface.slotRanges.out',
      size: 8 * n,
      usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC,
    });
    const staging = device.createBuffer({
      label: 'Isosurface.slotRanges.staging',
      size: 8 * n,
      usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST,
    });
    const group = bindGroup(device, 'Isosurface.slotRanges.bindGroup', this.layout, [this.blockRanges, list, this.#params, out]);
    this.#scratch = { slots: n, list, out, staging, group };
    return this.#scratch;
  }

  destroy(): void {
    if (this.#destroyed) return;
    this.#destroyed = true;
    const s = this.#scratch;
    if (s) for (const b of [s.list, s.out, s.staging]) b.destroy();
    this.#scratch = null;
    this.#params.destroy();
  }
}
