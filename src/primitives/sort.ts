// Stable radix sort by u32 key with u32 values, ascending or descending, the
// count from a GPU buffer. 4 bits per pass (keyBits / 4 passes, 8 for full
// keys); each pass is histogram -> ExclusiveScan of the digit table ->
// scatter, all sized on the GPU. Two kernel families with the same bindings
// (choosePath): per-invocation chunks (shaders/primitives/radix_sort.wgsl,
// emulator path) or per-workgroup tiles with workgroup histograms and
// workgroup-local stable ranking (radix_sort_tiled.wgsl, GPU path).

import sortWgsl from '../../shaders/primitives/radix_sort.wgsl?raw';
import sortCommonWgsl from '../../shaders/primitives/radix_sort_common.wgsl?raw';
import sortTiledWgsl from '../../shaders/primitives/radix_sort_tiled.wgsl?raw';
import { BindGroupCache } from '../gpu/bind-group-cache.ts';
import { gridSnippet } from '../gpu/dispatch.ts';
import { bindGroupLayout, createComputePipeline } from '../gpu/pipeline-cache.ts';
import type { WgslPart } from '../gpu/wgsl.ts';
import type { CountLike } from './count.ts';
import {
  DispatchRecords,
  RECORD_TABLE_COUNT,
  RECORD_UNIFORM_SIZE,
  choosePath,
  gpuPathWorkgroupSize,
  maxWorkgroupsPerDimension,
  tileConstants,
  workgroupSize,
  type PrimitiveOptions,
  type PrimitivePath,
} from './dispatch-records.ts';
import { ExclusiveScan } from './scan.ts';

/** The uniforms, bindings and digit() both kernel families share. */
const sortCommonSnippet: WgslPart = { name: 'shaders/primitives/radix_sort_common.wgsl', code: sortCommonWgsl };

const RADIX_BITS = 4;
const RADIX = 1 << RADIX_BITS;
const MAX_PASSES = 32 / RADIX_BITS;
/** Bytes between the per-pass uniforms (shift, mask, flip). */
const PASS_STRIDE = 256;
/** Per-pass uniforms: direction x pass x digit width (1..RADIX_BITS bits). */
const PASS_RECORDS = 2 * MAX_PASSES * RADIX_BITS;

function passRecord(descending: boolean, pass: number, bits: number): number {
  return ((descending ? MAX_PASSES : 0) + pass) * RADIX_BITS + bits - 1;
}

export interface RadixSortOptions extends PrimitiveOptions {
  /** Most elements one encode may sort; grow() raises it. */
  capacity: number;
  /**
   * Emulator path: consecutive elements per invocation, 1..255 (default 128).
   * GPU path: elements per invocation in a tile of workgroupSize * chunk,
   * 1..4096 (default 8). The digit table has 16 entries per chunk or tile.
   */
  chunk?: number;
}

export interface RadixSortArgs {
  /** u32 keys; STORAGE usage (and COPY_SRC/COPY_DST not needed). Sorted in place unless keysOut is given. */
  keys: GPUBuffer;
  /** u32 values, permuted with their keys; STORAGE usage. */
  values: GPUBuffer;
  /** Output buffers (both or neither); the inputs are then left unchanged. STORAGE usage. */
  keysOut?: GPUBuffer;
  valuesOut?: GPUBuffer;
  /** Elements to sort (clamped to the capacity). A GpuCount's buffer needs COPY_SRC. */
  count: CountLike;
  /** Largest keys first (still stable: equal keys keep their input order). */
  descending?: boolean;
  /** Only the low keyBits bits of the keys are compared (1..32, default 32); ceil(keyBits / 4) passes. */
  keyBits?: number;
}

interface Pair {
  keys: GPUBuffer;
  values: GPUBuffer;
}

export class RadixSortByKey {
  /** Elements per digit-table column: a chunk (emulator path) or a tile (GPU path). */
  readonly chunk: number;
  private capacityValue = 0;
  private keysTmp!: GPUBuffer;
  private valuesTmp!: GPUBuffer;
  private histograms!: GPUBuffer;
  private offsets!: GPUBuffer;
  private readonly histogramGroups = new BindGroupCache();
  private readonly scatterGroups = new BindGroupCache();

  private constructor(
    private readonly device: GPUDevice,
    private readonly histogramLayout: GPUBindGroupLayout,
    private readonly scatterLayout: GPUBindGroupLayout,
    private readonly histogramPipeline: GPUComputePipeline,
    private readonly scatterPipeline: GPUComputePipeline,
    private readonly copyPipeline: GPUComputePipeline,
    private readonly records: DispatchRecords,
    private readonly scan: ExclusiveScan,
    private readonly passParams: GPUBuffer,
    chunk: number,
    capacity: number,
    /** The kernel family in use (choosePath); the digit-table scan follows the same options. */
    readonly path: PrimitivePath,
  ) {
    this.chunk = chunk;
    this.allocate(capacity);
  }

  /** Whether the digit-table scan uses subgroup operations. */
  get subgroups(): boolean {
    return this.scan.subgroups;
  }

  static async create(device: GPUDevice, options: RadixSortOptions): Promise<RadixSortByKey> {
    const path = choosePath(device, options);
    const gpu = path === 'gpu';
    const items = options.chunk ?? (gpu ? 8 : 128);
    const maxItems = gpu ? 4096 : 255;
    if (!Number.isInteger(items) || items < 1 || items > maxItems) throw new RangeError(`chunk must be in 1..${maxItems}`);
    const wg = gpu ? gpuPathWorkgroupSize(device, options) : workgroupSize(device, options);
    // Elements per table column; on the GPU path one unit (tile) is one workgroup.
    const chunk = gpu ? wg * items : items;
    const maxPerDim = maxWorkgroupsPerDimension(device, options);
    const uniform = (dynamic: boolean): GPUBindGroupLayoutEntry['buffer'] => ({
      type: 'uniform',
      hasDynamicOffset: dynamic,
      minBindingSize: RECORD_UNIFORM_SIZE,
    });
    const entry = (binding: number, buffer: GPUBindGroupLayoutEntry['buffer']): GPUBindGroupLayoutEntry => ({
      binding,
      visibility: GPUShaderStage.COMPUTE,
      buffer,
    });
    const histogramLayout = bindGroupLayout(device, 'RadixSortByKey.histogramLayout', [
      entry(0, uniform(false)),
      entry(1, uniform(true)),
      entry(2, { type: 'read-only-storage' }),
      entry(4, { type: 'storage' }),
    ]);
    const scatterLayout = bindGroupLayout(device, 'RadixSortByKey.scatterLayout', [
      entry(0, uniform(false)),
      entry(1, uniform(true)),
      entry(2, { type: 'read-only-storage' }),
      entry(3, { type: 'read-only-storage' }),
      entry(5, { type: 'read-only-storage' }),
      entry(6, { type: 'storage' }),
      entry(7, { type: 'storage' }),
    ]);
    const parts = gpu
      ? [
          tileConstants(wg, items),
          gridSnippet,
          sortCommonSnippet,
          { name: 'shaders/primitives/radix_sort_tiled.wgsl', code: sortTiledWgsl },
        ]
      : [gridSnippet, sortCommonSnippet, { name: 'shaders/primitives/radix_sort.wgsl', code: sortWgsl }];
    const constants: Record<string, number> = gpu ? {} : { WG: wg, CHUNK: chunk };
    const [histogram, scatter, copy, records, scan] = await Promise.all([
      createComputePipeline(device, 'RadixSortByKey.histogram', parts, 'histogram', { layout: [histogramLayout], constants }),
      createComputePipeline(device, 'RadixSortByKey.scatter', parts, 'scatter', { layout: [scatterLayout], constants }),
      createComputePipeline(device, 'RadixSortByKey.copyBack', parts, 'copy_back', { layout: [scatterLayout], constants }),
      DispatchRecords.create(device, 'RadixSortByKey', {
        chunk,
        wg: gpu ? 1 : wg,
        levels: 1,
        capacity: options.capacity,
        maxWorkgroupsPerDimension: maxPerDim,
        tableRows: RADIX,
      }),
      ExclusiveScan.create(device, {
        capacity: RadixSortByKey.tableSize(options.capacity, chunk),
        maxWorkgroupsPerDimension: options.maxWorkgroupsPerDimension,
        workgroupSize: options.workgroupSize,
        path,
        subgroups: options.subgroups,
      }),
    ]);
    // Per-pass uniforms, written once; an encode picks them by dynamic offset.
    const passParams = device.createBuffer({
      label: 'RadixSortByKey.passParams',
      size: PASS_RECORDS * PASS_STRIDE,
      usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST,
    });
    const words = new Uint32Array((PASS_RECORDS * PASS_STRIDE) / 4);
    for (const descending of [false, true]) {
      for (let p = 0; p < MAX_PASSES; p++) {
        for (let bits = 1; bits <= RADIX_BITS; bits++) {
          const at = (passRecord(descending, p, bits) * PASS_STRIDE) / 4;
          const mask = (1 << bits) - 1;
          words.set([p * RADIX_BITS, mask, descending ? mask : 0], at);
        }
      }
    }
    device.queue.writeBuffer(passParams, 0, words);
    return new RadixSortByKey(
      device,
      histogramLayout,
      scatterLayout,
      histogram,
      scatter,
      copy,
      records,
      scan,
      passParams,
      chunk,
      options.capacity,
      path,
    );
  }

  private static tableSize(capacity: number, chunk: number): number {
    return RADIX * Math.ceil(Math.max(1, capacity) / chunk);
  }

  get capacity(): number {
    return this.capacityValue;
  }

  /** Raises the capacity (reallocating scratch); never shrinks. Call between submissions. */
  grow(capacity: number): void {
    if (capacity <= this.capacityValue) return;
    for (const b of [this.keysTmp, this.valuesTmp, this.histograms, this.offsets]) b.destroy();
    this.allocate(capacity);
  }

  private allocate(capacity: number): void {
    if (!Number.isInteger(capacity) || capacity < 0 || capacity > 0xffffffff) throw new RangeError(`capacity ${capacity} is not a u32`);
    this.capacityValue = capacity;
    const storage = GPUBufferUsage.STORAGE;
    const words = Math.max(1, capacity);
    const table = RadixSortByKey.tableSize(capacity, this.chunk);
    this.keysTmp = this.device.createBuffer({ label: 'RadixSortByKey.keysTmp', size: words * 4, usage: storage });
    this.valuesTmp = this.device.createBuffer({ label: 'RadixSortByKey.valuesTmp', size: words * 4, usage: storage });
    this.histograms = this.device.createBuffer({ label: 'RadixSortByKey.histograms', size: table * 4, usage: storage });
    this.offsets = this.device.createBuffer({ label: 'RadixSortByKey.offsets', size: table * 4, usage: storage });
    this.scan.grow(table);
    this.records.setCapacity(capacity);
    this.histogramGroups.clear();
    this.scatterGroups.clear();
  }

  private histogramGroup(src: Pair): GPUBindGroup {
    return this.histogramGroups.key(src.keys).get(() =>
      this.device.createBindGroup({
        label: 'RadixSortByKey.histogramBindGroup',
        layout: this.histogramLayout,
        entries: [
          { binding: 0, resource: { buffer: this.records.params, size: RECORD_UNIFORM_SIZE } },
          { binding: 1, resource: { buffer: this.passParams, size: RECORD_UNIFORM_SIZE } },
          { binding: 2, resource: { buffer: src.keys } },
          { binding: 4, resource: { buffer: this.histograms } },
        ],
      }),
    );
  }

  private scatterGroup(src: Pair, dst: Pair): GPUBindGroup {
    return this.scatterGroups
      .key(src.keys)
      .key(src.values)
      .key(dst.keys)
      .key(dst.values)
      .get(() =>
        this.device.createBindGroup({
          label: 'RadixSortByKey.scatterBindGroup',
          layout: this.scatterLayout,
          entries: [
            { binding: 0, resource: { buffer: this.records.params, size: RECORD_UNIFORM_SIZE } },
            { binding: 1, resource: { buffer: this.passParams, size: RECORD_UNIFORM_SIZE } },
            { binding: 2, resource: { buffer: src.keys } },
            { binding: 3, resource: { buffer: src.values } },
            { binding: 5, resource: { buffer: this.offsets } },
            { binding: 6, resource: { buffer: dst.keys } },
            { binding: 7, resource: { buffer: dst.values } },
          ],
        }),
      );
  }

  /** Records the sort: about 3 compute passes per 4 key bits, no readback. */
  encode(encoder: GPUCommandEncoder, args: RadixSortArgs): void {
    const keyBits = args.keyBits ?? 32;
    if (!Number.isInteger(keyBits) || keyBits < 1 || keyBits > 32) throw new RangeError('keyBits must be in 1..32');
    if ((args.keysOut === undefined) !== (args.valuesOut === undefined))
      throw new Error('RadixSortByKey: give both keysOut and valuesOut, or neither');
    if (args.keys === args.values) throw new Error('RadixSortByKey: keys and values must be different buffers');
    const input: Pair = { keys: args.keys, values: args.values };
    const output: Pair = args.keysOut && args.valuesOut ? { keys: args.keysOut, values: args.valuesOut } : input;
    const inPlace = output.keys === input.keys && output.values === input.values;
    if (
      !inPlace &&
      (output.keys === input.keys || output.values === input.values || output.keys === input.values || output.values === input.keys)
    ) {
      throw new Error('RadixSortByKey: outputs must be the inputs (in place) or distinct from them');
    }
    const scratch: Pair = { keys: this.keysTmp, values: this.valuesTmp };
    const passes = Math.ceil(keyBits / RADIX_BITS);
    // Ping-pong so that the last pass writes `output`; an in-place sort with
    // an odd number of passes ends in scratch and copies back.
    const copyBack = inPlace && passes % 2 === 1;
    const last = copyBack ? scratch : output;
    const other = copyBack ? output : scratch;
    const descending = args.descending ?? false;
    const params = this.records.params;
    const argsOffset = DispatchRecords.argsOffset(0);

    this.records.encodeCount(encoder, args.count);
    let pass = encoder.beginComputePass({ label: 'RadixSortByKey.setup' });
    this.records.dispatchSetup(pass);
    pass.end();
    let src = input;
    for (let p = 0; p < passes; p++) {
      const dst = (passes - 1 - p) % 2 === 0 ? last : other;
      const passOffset = [passRecord(descending, p, Math.min(RADIX_BITS, keyBits - p * RADIX_BITS)) * PASS_STRIDE];
      pass = encoder.beginComputePass({ label: 'RadixSortByKey.histogram' });
      pass.setPipeline(this.histogramPipeline);
      pass.setBindGroup(0, this.histogramGroup(src), passOffset);
      pass.dispatchWorkgroupsIndirect(params, argsOffset);
      pass.end();
      this.scan.encode(encoder, {
        input: this.histograms,
        output: this.offsets,
        count: { buffer: params, offset: RECORD_TABLE_COUNT },
      });
      pass = encoder.beginComputePass({ label: 'RadixSortByKey.scatter' });
      pass.setPipeline(this.scatterPipeline);
      pass.setBindGroup(0, this.scatterGroup(src, dst), passOffset);
      pass.dispatchWorkgroupsIndirect(params, argsOffset);
      pass.end();
      src = dst;
    }
    if (copyBack) {
      pass = encoder.beginComputePass({ label: 'RadixSortByKey.copyBack' });
      pass.setPipeline(this.copyPipeline);
      pass.setBindGroup(0, this.scatterGroup(scratch, output), [0]);
      pass.dispatchWorkgroupsIndirect(params, argsOffset);
      pass.end();
    }
  }

  destroy(): void {
    for (const b of [this.keysTmp, this.valuesTmp, this.histograms, this.offsets, this.passParams]) b.destroy();
    this.records.destroy();
    this.scan.destroy();
  }
}
