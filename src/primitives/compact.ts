// Stream compaction driven by a GPU-side count: StreamCompact (values) and
// StreamCompactIds (indices), from a 0/1 mask and its exclusive scan.

import compactWgsl from '../../shaders/primitives/compact.wgsl?raw';
import compactTiledWgsl from '../../shaders/primitives/compact_tiled.wgsl?raw';
import { BindGroupCache } from '../gpu/bind-group-cache.ts';
import { gridSnippet } from '../gpu/dispatch.ts';
import { createComputePipeline } from '../gpu/pipeline-cache.ts';
import type { CountLike } from './count.ts';
import {
  DispatchRecords,
  RECORD_UNIFORM_SIZE,
  choosePath,
  gpuPathWorkgroupSize,
  maxWorkgroupsPerDimension,
  tileConstants,
  workgroupSize,
  type PrimitiveOptions,
  type PrimitivePath,
} from './dispatch-records.ts';

export interface CompactOptions extends PrimitiveOptions {
  /**
   * Elements per invocation: consecutive ones on the emulator path (default
   * 16), WG apart in a tile of workgroupSize * chunk on the GPU path (default 4).
   */
  chunk?: number;
}

export interface StreamCompactIdsArgs {
  /** u32 per element: 1 = keep, 0 = drop; STORAGE usage. */
  mask: GPUBuffer;
  /** Exclusive scan of the 0/1 mask (kept elements of one chunk go to consecutive slots from its first offset), e.g. from ExclusiveScan; STORAGE usage. */
  offsets: GPUBuffer;
  /** Receives the kept elements at offsets[i]; STORAGE usage. Nothing else is written. */
  output: GPUBuffer;
  /** Elements of mask/offsets to consider. A GpuCount's buffer needs COPY_SRC. */
  count: CountLike;
  timestampWrites?: GPUComputePassTimestampWrites;
}

export interface StreamCompactArgs extends StreamCompactIdsArgs {
  /** u32 values, one per element; STORAGE usage. */
  values: GPUBuffer;
}

/** Shared body of both compactions: one pipeline, one dispatch record. */
class Compaction {
  private readonly bindGroups = new BindGroupCache();

  constructor(
    private readonly device: GPUDevice,
    private readonly label: string,
    private readonly pipeline: GPUComputePipeline,
    private readonly records: DispatchRecords,
    readonly path: PrimitivePath,
  ) {}

  static async create(device: GPUDevice, label: string, entryPoint: string, options: CompactOptions): Promise<Compaction> {
    const path = choosePath(device, options);
    const gpu = path === 'gpu';
    const chunk = options.chunk ?? (gpu ? 4 : 16);
    if (!Number.isInteger(chunk) || chunk < 1 || chunk > 4096) throw new RangeError('chunk must be in 1..4096');
    const wg = gpu ? gpuPathWorkgroupSize(device, options) : workgroupSize(device, options);
    const parts = gpu
      ? [tileConstants(wg, chunk), gridSnippet, { name: 'shaders/primitives/compact_tiled.wgsl', code: compactTiledWgsl }]
      : [gridSnippet, { name: 'shaders/primitives/compact.wgsl', code: compactWgsl }];
    const [pipeline, records] = await Promise.all([
      createComputePipeline(device, `${label}.compact`, parts, entryPoint, { constants: gpu ? {} : { WG: wg, CHUNK: chunk } }),
      // GPU path: one unit is a tile, one workgroup.
      DispatchRecords.create(device, label, {
        chunk: gpu ? wg * chunk : chunk,
        wg: gpu ? 1 : wg,
        levels: 1,
        capacity: 0xffffffff,
        maxWorkgroupsPerDimension: maxWorkgroupsPerDimension(device, options),
      }),
    ]);
    return new Compaction(device, label, pipeline, records, path);
  }

  encode(encoder: GPUCommandEncoder, args: StreamCompactIdsArgs, values?: GPUBuffer): void {
    const { mask, offsets, output } = args;
    if (output === mask || output === offsets || output === values) throw new Error(`${this.label}: output must not alias an input`);
    // Keyed by (mask, offsets, output, values or mask): no array per call.
    const bindGroup = this.bindGroups
      .key(mask)
      .key(offsets)
      .key(output)
      .key(values ?? mask)
      .get(() =>
        this.device.createBindGroup({
          label: `${this.label}.bindGroup`,
          layout: this.pipeline.getBindGroupLayout(0),
          entries: [
            { binding: 0, resource: { buffer: this.records.params, size: RECORD_UNIFORM_SIZE } },
            { binding: 1, resource: { buffer: mask } },
            { binding: 2, resource: { buffer: offsets } },
            ...(values ? [{ binding: 3, resource: { buffer: values } }] : []),
            { binding: 4, resource: { buffer: output } },
          ],
        }),
      );
    this.records.encodeCount(encoder, args.count);
    const pass = encoder.beginComputePass({ label: this.label, timestampWrites: args.timestampWrites });
    this.records.dispatchSetup(pass);
    pass.setPipeline(this.pipeline);
    pass.setBindGroup(0, bindGroup);
    pass.dispatchWorkgroupsIndirect(this.records.params, DispatchRecords.argsOffset(0));
    pass.end();
  }

  destroy(): void {
    this.records.destroy();
  }
}

/** out[offsets[i]] = values[i] for every i < count with mask[i] != 0. */
export class StreamCompact {
  private constructor(private readonly impl: Compaction) {}

  static async create(device: GPUDevice, options: CompactOptions = {}): Promise<StreamCompact> {
    return new StreamCompact(await Compaction.create(device, 'StreamCompact', 'compact_values', options));
  }

  /** The kernel family in use (choosePath). */
  get path(): PrimitivePath {
    return this.impl.path;
  }

  encode(encoder: GPUCommandEncoder, args: StreamCompactArgs): void {
    this.impl.encode(encoder, args, args.values);
  }

  destroy(): void {
    this.impl.destroy();
  }
}

/** out[offsets[i]] = i for every i < count with mask[i] != 0 (the paper's StreamCompactIDs). */
export class StreamCompactIds {
  private constructor(private readonly impl: Compaction) {}

  static async create(device: GPUDevice, options: CompactOptions = {}): Promise<StreamCompactIds> {
    return new StreamCompactIds(await Compaction.create(device, 'StreamCompactIds', 'compact_ids', options));
  }

  /** The kernel family in use (choosePath). */
  get path(): PrimitivePath {
    return this.impl.path;
  }

  encode(encoder: GPUCommandEncoder, args: StreamCompactIdsArgs): void {
    this.impl.encode(encoder, args);
  }

  destroy(): void {
    this.impl.destroy();
  }
}
