// Dispatch records: the parameter block every primitive keeps on the GPU.
// A record is 8 u32 words [n, units, capacity, count_in, x, y, z, extra], one per
// level, 256 bytes apart so each can be bound as a uniform with a dynamic
// offset and read by dispatchWorkgroupsIndirect at byte 16. The count is
// copied in (encoder-ordered); a one-thread setup kernel fills the rest.

import setupWgsl from '../../shaders/primitives/setup.wgsl?raw';
import { summarizeAdapter } from '../gpu/device.ts';
import { gridSnippet } from '../gpu/dispatch.ts';
import { createComputePipeline } from '../gpu/pipeline-cache.ts';
import type { WgslPart } from '../gpu/wgsl.ts';
import { encodeCountCopy, type CountLike } from './count.ts';

/** Bytes between records (a multiple of every minUniformBufferOffsetAlignment). */
export const RECORD_STRIDE = 256;
/** Byte offsets inside a record. */
export const RECORD_N = 0;
export const RECORD_CAPACITY = 8;
export const RECORD_COUNT_IN = 12;
export const RECORD_ARGS = 16;
/** Record 0 only: units * tableRows (see setup.wgsl). */
export const RECORD_TABLE_COUNT = 28;
/** Bytes a kernel binds as its uniform `Level`/`Dispatch` struct. */
export const RECORD_UNIFORM_SIZE = 16;

// A function: in Node the GPUBufferUsage global exists only once Dawn is loaded.
export function paramsUsage(): GPUBufferUsageFlags {
  return GPUBufferUsage.STORAGE | GPUBufferUsage.UNIFORM | GPUBufferUsage.INDIRECT | GPUBufferUsage.COPY_DST | GPUBufferUsage.COPY_SRC;
}

/** Options shared by every primitive. */
export interface PrimitiveOptions {
  /** Grid limit per dimension (default: the device's). Tests lower it to exercise 2D grids. */
  maxWorkgroupsPerDimension?: number;
  /** Invocations per workgroup (default 64 on the emulator path, 256 on the GPU path; capped by the device's limits). */
  workgroupSize?: number;
  /** Kernel family: 'auto' (default) picks per adapter, see choosePath. */
  path?: PrimitivePath | 'auto';
  /**
   * GPU path only: workgroup scans with subgroup operations. Default: where
   * the device has the 'subgroups' feature; false forces the workgroup-memory
   * scan; true requires the feature.
   */
  subgroups?: boolean;
}

/**
 * 'emulator': one contiguous chunk per invocation, no workgroup memory or
 * barriers (what runs fast on SwiftShader and other CPU implementations).
 * 'gpu': tiles of consecutive elements per workgroup, consecutive invocations
 * on consecutive elements (coalesced), workgroup-shared-memory scans.
 */
export type PrimitivePath = 'emulator' | 'gpu';

/**
 * The path for this device: the option if it names one, else 'emulator' on
 * CPU implementations (SwiftShader, llvmpipe, lavapipe, WARP: see
 * summarizeAdapter) and 'gpu' everywhere else (also when the implementation
 * does not expose device.adapterInfo).
 */
export function choosePath(device: GPUDevice, options: PrimitiveOptions): PrimitivePath {
  const p = options.path ?? 'auto';
  if (p === 'emulator' || p === 'gpu') return p;
  if (p !== 'auto') throw new RangeError(`path must be 'auto', 'emulator' or 'gpu' (got ${String(p)})`);
  const info = (device as GPUDevice & { adapterInfo?: GPUAdapterInfo }).adapterInfo;
  return summarizeAdapter(info).software ? 'emulator' : 'gpu';
}

/**
 * Whether a GPU-path kernel uses subgroup operations (see
 * PrimitiveOptions.subgroups); never on the emulator path.
 */
export function chooseSubgroups(device: GPUDevice, options: PrimitiveOptions, path: PrimitivePath): boolean {
  const has = device.features.has('subgroups' as GPUFeatureName);
  if (options.subgroups === true && !has) throw new RangeError("subgroups: true needs a device with the 'subgroups' feature");
  return path === 'gpu' && has && options.subgroups !== false;
}

/** Invocations per workgroup of the GPU path (default 256, capped by the limits). */
export function gpuPathWorkgroupSize(device: GPUDevice, options: PrimitiveOptions): number {
  return workgroupSize(device, { ...options, workgroupSize: options.workgroupSize ?? 256 });
}

/**
 * WGSL constants of a GPU-path kernel: `const`, not `override`, because they
 * size workgroup arrays (override-sized arrays are not portable to naga).
 */
export function tileConstants(wg: number, items: number): WgslPart {
  return { name: 'tile constants', code: `const WG: u32 = ${wg}u;\nconst ITEMS: u32 = ${items}u;\nconst TILE: u32 = ${wg * items}u;\n` };
}

export function maxWorkgroupsPerDimension(device: GPUDevice, options: PrimitiveOptions): number {
  const limit = device.limits.maxComputeWorkgroupsPerDimension;
  const v = options.maxWorkgroupsPerDimension ?? limit;
  if (!Number.isInteger(v) || v < 1 || v > limit) throw new RangeError(`maxWorkgroupsPerDimension must be in 1..${limit}`);
  return v;
}

/** On the emulator path the kernels use no workgroup memory and no barriers: the size only sets the grid's granularity. */
export function workgroupSize(device: GPUDevice, options: PrimitiveOptions): number {
  const max = Math.min(device.limits.maxComputeInvocationsPerWorkgroup, device.limits.maxComputeWorkgroupSizeX);
  const wg = options.workgroupSize ?? Math.min(64, max);
  if (!Number.isInteger(wg) || wg < 1 || wg > max) throw new RangeError(`workgroupSize must be in 1..${max}`);
  return wg;
}

/** The params buffer of a primitive and the kernel that fills its records. */
export class DispatchRecords {
  readonly params: GPUBuffer;
  private readonly bindGroup: GPUBindGroup;
  private readonly word = new Uint32Array(1);

  private constructor(
    private readonly device: GPUDevice,
    private readonly pipeline: GPUComputePipeline,
    readonly levels: number,
    label: string,
    capacity: number,
  ) {
    this.params = device.createBuffer({ label: `${label}.params`, size: levels * RECORD_STRIDE, usage: paramsUsage() });
    this.bindGroup = device.createBindGroup({
      label: `${label}.setupBindGroup`,
      layout: pipeline.getBindGroupLayout(0),
      entries: [{ binding: 0, resource: { buffer: this.params } }],
    });
    this.setCapacity(capacity);
  }

  /**
   * @param chunk elements per invocation at every level
   * @param wg invocations per workgroup
   * @param levels records to fill (record l+1 counts the chunks of record l)
   */
  static async create(
    device: GPUDevice,
    label: string,
    opts: { chunk: number; wg: number; levels: number; capacity: number; maxWorkgroupsPerDimension: number; tableRows?: number },
  ): Promise<DispatchRecords> {
    const pipeline = await createComputePipeline(
      device,
      `${label}.setup`,
      [gridSnippet, { name: 'shaders/primitives/setup.wgsl', code: setupWgsl }],
      'setup_dispatch',
      {
        constants: {
          CHUNK: opts.chunk,
          WG: opts.wg,
          LEVELS: opts.levels,
          MAX_WG_PER_DIM: opts.maxWorkgroupsPerDimension,
          TABLE_ROWS: opts.tableRows ?? 0,
        },
      },
    );
    return new DispatchRecords(device, pipeline, opts.levels, label, opts.capacity);
  }

  /** Counts above `capacity` are clamped to it. Queue-ordered: call between submissions. */
  setCapacity(capacity: number): void {
    this.word[0] = Math.min(capacity, 0xffffffff);
    this.device.queue.writeBuffer(this.params, RECORD_CAPACITY, this.word);
  }

  /** Records the copy of the count into record 0. Call outside a pass. */
  encodeCount(encoder: GPUCommandEncoder, count: CountLike): void {
    encodeCountCopy(this.device, encoder, count, this.params, RECORD_COUNT_IN);
  }

  /** Records the one-thread setup dispatch into a compute pass. */
  dispatchSetup(pass: GPUComputePassEncoder): void {
    pass.setPipeline(this.pipeline);
    pass.setBindGroup(0, this.bindGroup);
    pass.dispatchWorkgroups(1);
  }

  /** Byte offset of level l's record (its uniform binding offset). */
  static recordOffset(level: number): number {
    return level * RECORD_STRIDE;
  }

  /** Byte offset of level l's dispatchWorkgroupsIndirect arguments. */
  static argsOffset(level: number): number {
    return level * RECORD_STRIDE + RECORD_ARGS;
  }

  destroy(): void {
    this.params.destroy();
  }
}
