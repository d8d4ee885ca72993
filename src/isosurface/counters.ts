// The counters buffer (layout.ts): every count of one computation lives here,
// written by scans (totals), the plan kernels and the LRU kernels, and read by
// later dispatches (indirect arguments, gated counts) and, asynchronously, by
// the statistics readback. The host writes only the capacities (words 0-4).
import type { GpuCount } from '../gpu/buffer-ref.ts';
import { bindGroup, bufferLayout } from '../gpu/bindings.ts';
import { createComputePipeline } from '../gpu/pipeline-cache.ts';
import { C, COUNTERS_BYTES } from './layout.ts';
import { isosurfaceWgsl } from './wgsl.ts';

export type CounterName = keyof typeof C;

export class Counters {
  readonly buffer: GPUBuffer;
  private readonly group: GPUBindGroup;
  private readonly word = new Uint32Array(1);

  private constructor(
    private readonly device: GPUDevice,
    private readonly planCache: GPUComputePipeline,
    private readonly planUpdate: GPUComputePipeline,
    private readonly planGroups: GPUComputePipeline,
    layout: GPUBindGroupLayout,
  ) {
    this.buffer = device.createBuffer({
      label: 'Isosurface.counters',
      size: COUNTERS_BYTES,
      usage: GPUBufferUsage.STORAGE | GPUBufferUsage.UNIFORM | GPUBufferUsage.INDIRECT | GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST,
    });
    this.group = bindGroup(device, 'Isosurface.counters.bindGroup', layout, [this.buffer]);
  }

  static async create(device: GPUDevice, maxWorkgroupsPerDimension: number): Promise<Counters> {
    const layout = bufferLayout(device, 'Isosurface.plan.layout', ['rw']);
    const constants = { MAX_WG_PER_DIM: maxWorkgroupsPerDimension };
    const [cache, update, groups] = await Promise.all([
      createComputePipeline(device, 'Isosurface.planCache', isosurfaceWgsl.plan, 'plan_cache', { layout: [layout], constants }),
      createComputePipeline(device, 'Isosurface.planUpdate', isosurfaceWgsl.plan, 'plan_update', { layout: [layout], constants }),
      createComputePipeline(device, 'Isosurface.planGroups', isosurfaceWgsl.plan, 'plan_groups', { layout: [layout], constants }),
    ]);
    return new Counters(device, cache, update, groups, layout);
  }

  /** The counter as a GpuCount (for the primitives and the decoder). */
  count(name: CounterName): GpuCount {
    return { buffer: this.buffer, offset: C[name] * 4 };
  }

  /** Byte offset of a word (indirect arguments). */
  static offset(word: number): number {
    return word * 4;
  }

  /** Host-written words (capacities); queue-ordered, so call between submissions. */
  set(
    name:
      | 'blocks'
      | 'slots'
      | 'vertexCapacity'
      | 'weldedCapacity'
      | 'cellCapacity'
      | 'groups'
      | 'groupSize'
      | 'shards'
      | 'perShard'
      | 'slotsUsed'
      | 'status'
      | 'request'
      | 'logSize',
    value: number,
  ): void {
    this.word[0] = value;
    this.device.queue.writeBuffer(this.buffer, C[name] * 4, this.word);
  }

  /** Records plan_cache (is the cache large enough; gated counts and arguments). */
  encodePlanCache(pass: GPUComputePassEncoder): void {
    pass.setPipeline(this.planCache);
    pass.setBindGroup(0, this.group);
    pass.dispatchWorkgroups(1);
  }

  /** Records plan_groups (blocks of the active groups to test; their dispatch arguments). */
  encodePlanGroups(pass: GPUComputePassEncoder): void {
    pass.setPipeline(this.planGroups);
    pass.setBindGroup(0, this.group);
    pass.dispatchWorkgroups(1);
  }

  /** Records plan_update (exit if nothing is new; assignment arguments). */
  encodePlanUpdate(pass: GPUComputePassEncoder): void {
    pass.setPipeline(this.planUpdate);
    pass.setBindGroup(0, this.group);
    pass.dispatchWorkgroups(1);
  }

  destroy(): void {
    this.buffer.destroy();
  }
}
