// Exclusive scan (prefix sum) of u32, any length from 0 to the capacity, with
// the count in a GPU buffer and an optional total written to a GPU buffer.
// Design: multi-level reduce-then-scan (shaders/primitives/scan.wgsl); see
// src/primitives/README.md for why not single-pass.

import scanWgsl from '../../shaders/primitives/scan.wgsl?raw';
import scanTiledWgsl from '../../shaders/primitives/scan_tiled.wgsl?raw';
import workgroupScanWgsl from '../../shaders/primitives/workgroup_scan.wgsl?raw';
import workgroupScanSubgroupsWgsl from '../../shaders/primitives/workgroup_scan_subgroups.wgsl?raw';
import { KeyedCache } from '../gpu/bind-group-cache.ts';
import { binding, type GpuBufferRef, type GpuCount, refBuffer } from '../gpu/buffer-ref.ts';
import { gridSnippet } from '../gpu/dispatch.ts';
import { bindGroupLayout, createComputePipeline } from '../gpu/pipeline-cache.ts';
import type { WgslPart } from '../gpu/wgsl.ts';
import type { CountLike } from './count.ts';
import {
  DispatchRecords,
  RECORD_UNIFORM_SIZE,
  choosePath,
  chooseSubgroups,
  gpuPathWorkgroupSize,
  maxWorkgroupsPerDimension,
  tileConstants,
  workgroupSize,
  type PrimitiveOptions,
  type PrimitivePath,
} from './dispatch-records.ts';

const scanSnippet: WgslPart = { name: 'shaders/primitives/scan.wgsl', code: scanWgsl };
const scanTiledSnippet: WgslPart = { name: 'shaders/primitives/scan_tiled.wgsl', code: scanTiledWgsl };
const workgroupScanSnippet: WgslPart = { name: 'shaders/primitives/workgroup_scan.wgsl', code: workgroupScanWgsl };
const workgroupScanSubgroupsSnippet: WgslPart = {
  name: 'shaders/primitives/workgroup_scan_subgroups.wgsl',
  code: workgroupScanSubgroupsWgsl,
};

/**
 * Workgroup-memory words of the GPU path's scan kernel: the tile with
 * padding, plus two Kogge-Stone halves or (with subgroups) two counters and
 * a first place and a total per subgroup of at least 4.
 */
export function tiledScanWords(wg: number, items: number, subgroups = false): number {
  const t = wg * items;
  return t + Math.floor(t / 32) + 1 + (subgroups ? 2 + 2 * Math.ceil(wg / 4) : 2 * wg);
}

export interface ExclusiveScanOptions extends PrimitiveOptions {
  /** Most elements one encode may scan; grow() raises it. */
  capacity: number;
  /**
   * Emulator path: consecutive elements per invocation (and per partial sum),
   * default 16. GPU path: elements per invocation in a tile of
   * workgroupSize * chunk (one partial sum per tile), default 4.
   */
  chunk?: number;
}

export interface ExclusiveScanArgs {
  /** u32 elements (a buffer, or a range of one); needs STORAGE usage. Not the same buffer as `output`. */
  input: GpuBufferRef;
  /** Receives the exclusive prefix sums of the first `count` elements (a buffer or a range); STORAGE usage. */
  output: GpuBufferRef;
  /** Elements to scan (clamped to the capacity). A GpuCount's buffer needs COPY_SRC. */
  count: CountLike;
  /** Where to write the sum of all `count` elements; its buffer needs COPY_DST. */
  totalOut?: GpuCount;
  timestampWrites?: GPUComputePassTimestampWrites;
}

interface UserBindGroups {
  reduce?: GPUBindGroup;
  scan: GPUBindGroup;
}

/** Levels until one chunk holds the rest (the top level, one invocation). */
function levelsFor(capacity: number, chunk: number): number {
  let levels = 1;
  for (let n = Math.max(1, capacity); n > chunk; n = Math.ceil(n / chunk)) levels++;
  return levels;
}

export class ExclusiveScan {
  /** Elements per partial sum: a chunk (emulator path) or a tile (GPU path). */
  readonly chunk: number;
  private capacityValue = 0;
  private levels = 1;
  /** sums[l], scans[l] for levels l >= 1 (index 0 unused). */
  private sums: GPUBuffer[] = [];
  private scans: GPUBuffer[] = [];
  private internalReduce: GPUBindGroup[] = [];
  private internalScan: GPUBindGroup[] = [];
  private readonly userBindGroups = new KeyedCache<UserBindGroups>();
  private readonly zero: GPUBuffer;
  /** Each level's record offset (its dynamic uniform offset), so encode allocates nothing. */
  private readonly recordOffsets: Uint32Array<ArrayBuffer>;
  private readonly total: GPUBuffer;

  private constructor(
    private readonly device: GPUDevice,
    private readonly layout: GPUBindGroupLayout,
    private readonly reducePipeline: GPUComputePipeline,
    private readonly scanPipeline: GPUComputePipeline,
    private readonly records: DispatchRecords,
    chunk: number,
    capacity: number,
    /** The kernel family in use (choosePath). */
    readonly path: PrimitivePath,
    /** GPU path: whether the workgroup scans use subgroup operations (chooseSubgroups). */
    readonly subgroups: boolean,
  ) {
    this.chunk = chunk;
    this.recordOffsets = Uint32Array.from({ length: records.levels }, (_, l) => DispatchRecords.recordOffset(l));
    this.zero = device.createBuffer({ label: 'ExclusiveScan.zero', size: 4, usage: GPUBufferUsage.STORAGE });
    this.total = device.createBuffer({ label: 'ExclusiveScan.total', size: 4, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC });
    this.allocate(capacity);
  }

  static async create(device: GPUDevice, options: ExclusiveScanOptions): Promise<ExclusiveScan> {
    const path = choosePath(device, options);
    const gpu = path === 'gpu';
    const subgroups = chooseSubgroups(device, options, path);
    const items = options.chunk ?? (gpu ? 4 : 16);
    const wg = gpu ? gpuPathWorkgroupSize(device, options) : workgroupSize(device, options);
    if (!Number.isInteger(items) || items < (gpu ? 1 : 2) || items > 4096) throw new RangeError(`chunk must be in ${gpu ? 1 : 2}..4096`);
    if (gpu && (wg * items < 2 || tiledScanWords(wg, items, subgroups) * 4 > device.limits.maxComputeWorkgroupStorageSize)) {
      throw new RangeError(
        `ExclusiveScan: a tile of ${wg} x ${items} elements does not fit the workgroup storage limit (${device.limits.maxComputeWorkgroupStorageSize} B)`,
      );
    }
    // Elements per partial sum; on the GPU path one unit (tile) is one workgroup.
    const chunk = gpu ? wg * items : items;
    const maxPerDim = maxWorkgroupsPerDimension(device, options);
    const layout = bindGroupLayout(device, 'ExclusiveScan.layout', [
      {
        binding: 0,
        visibility: GPUShaderStage.COMPUTE,
        buffer: { type: 'uniform', hasDynamicOffset: true, minBindingSize: RECORD_UNIFORM_SIZE },
      },
      { binding: 1, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'read-only-storage' } },
      { binding: 2, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'storage' } },
      { binding: 3, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'read-only-storage' } },
      { binding: 4, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'storage' } },
    ]);
    // The subgroup twin goes first: it carries the `enable subgroups;` directive.
    const parts = !gpu
      ? [gridSnippet, scanSnippet]
      : subgroups
        ? [workgroupScanSubgroupsSnippet, tileConstants(wg, items), gridSnippet, scanTiledSnippet]
        : [tileConstants(wg, items), gridSnippet, workgroupScanSnippet, scanTiledSnippet];
    const constants: Record<string, number> = gpu ? {} : { WG: wg, CHUNK: chunk };
    const [reduce, scan, records] = await Promise.all([
      createComputePipeline(device, 'ExclusiveScan.reduce', parts, 'reduce', { layout: [layout], constants }),
      createComputePipeline(device, 'ExclusiveScan.scan', parts, 'scan', { layout: [layout], constants }),
      DispatchRecords.create(device, 'ExclusiveScan', {
        chunk,
        wg: gpu ? 1 : wg,
        levels: levelsFor(0xffffffff, chunk),
        capacity: options.capacity,
        maxWorkgroupsPerDimension: maxPerDim,
      }),
    ]);
    return new ExclusiveScan(device, layout, reduce, scan, records, chunk, options.capacity, path, subgroups);
  }

  get capacity(): number {
    return this.capacityValue;
  }

  /** Raises the capacity (reallocating scratch); never shrinks. Call between submissions. */
  grow(capacity: number): void {
    if (capacity <= this.capacityValue) return;
    this.allocate(capacity);
  }

  private allocate(capacity: number): void {
    if (!Number.isInteger(capacity) || capacity < 0 || capacity > 0xffffffff) throw new RangeError(`capacity ${capacity} is not a u32`);
    for (const b of [...this.sums, ...this.scans]) b?.destroy();
    this.capacityValue = capacity;
    this.levels = levelsFor(capacity, this.chunk);
    this.sums = [];
    this.scans = [];
    let n = Math.max(1, capacity);
    for (let l = 1; l < this.levels; l++) {
      n = Math.ceil(n / this.chunk);
      const usage = GPUBufferUsage.STORAGE;
      this.sums[l] = this.device.createBuffer({ label: `ExclusiveScan.sums${l}`, size: n * 4, usage });
      this.scans[l] = this.device.createBuffer({ label: `ExclusiveScan.scans${l}`, size: n * 4, usage });
    }
    this.internalReduce = [];
    this.internalScan = [];
    for (let l = 1; l < this.levels; l++) {
      const top = l === this.levels - 1;
      if (!top) this.internalReduce[l] = this.bindGroup(`reduce${l}`, this.sums[l], this.sums[l + 1], this.zero);
      this.internalScan[l] = this.bindGroup(`scan${l}`, this.sums[l], this.scans[l], top ? this.zero : this.scans[l + 1]);
    }
    this.userBindGroups.clear();
    this.records.setCapacity(capacity);
  }

  private bindGroup(name: string, src: GpuBufferRef, dst: GpuBufferRef, carry: GPUBuffer): GPUBindGroup {
    return this.device.createBindGroup({
      label: `ExclusiveScan.${name}`,
      layout: this.layout,
      entries: [
        { binding: 0, resource: { buffer: this.records.params, size: RECORD_UNIFORM_SIZE } },
        { binding: 1, resource: binding(src) },
        { binding: 2, resource: binding(dst) },
        { binding: 3, resource: { buffer: carry } },
        { binding: 4, resource: { buffer: this.total } },
      ],
    });
  }

  private userGroups(input: GpuBufferRef, output: GpuBufferRef): UserBindGroups {
    return this.userBindGroups
      .ref(input)
      .ref(output)
      .get(() => {
        const single = this.levels === 1;
        return {
          reduce: single ? undefined : this.bindGroup('reduce0', input, this.sums[1], this.zero),
          scan: this.bindGroup('scan0', input, output, single ? this.zero : this.scans[1]),
        };
      });
  }

  /** Records the scan: a count copy, one compute pass, and the total copy if asked. */
  encode(encoder: GPUCommandEncoder, args: ExclusiveScanArgs): void {
    if (refBuffer(args.input) === refBuffer(args.output)) throw new Error('ExclusiveScan: input and output must be different buffers');
    const user = this.userGroups(args.input, args.output);
    const params = this.records.params;
    this.records.encodeCount(encoder, args.count);
    const pass = encoder.beginComputePass({ label: 'ExclusiveScan', timestampWrites: args.timestampWrites });
    this.records.dispatchSetup(pass);
    const top = this.levels - 1;
    if (top > 0) {
      pass.setPipeline(this.reducePipeline);
      for (let l = 0; l < top; l++) {
        pass.setBindGroup(0, l === 0 ? user.reduce! : this.internalReduce[l], this.recordOffsets, l, 1);
        pass.dispatchWorkgroupsIndirect(params, DispatchRecords.argsOffset(l));
      }
    }
    pass.setPipeline(this.scanPipeline);
    // The top level holds at most one chunk or tile: one workgroup, even for count 0.
    pass.setBindGroup(0, top === 0 ? user.scan : this.internalScan[top], this.recordOffsets, top, 1);
    pass.dispatchWorkgroups(1);
    for (let l = top - 1; l >= 0; l--) {
      pass.setBindGroup(0, l === 0 ? user.scan : this.internalScan[l], this.recordOffsets, l, 1);
      pass.dispatchWorkgroupsIndirect(params, DispatchRecords.argsOffset(l));
    }
    pass.end();
    if (args.totalOut) encoder.copyBufferToBuffer(this.total, 0, args.totalOut.buffer, args.totalOut.offset, 4);
  }

  destroy(): void {
    for (const b of [...this.sums, ...this.scans]) b?.destroy();
    this.zero.destroy();
    this.total.destroy();
    this.records.destroy();
  }
}
