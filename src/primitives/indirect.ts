// dispatchWorkgroupsIndirect arguments from a GPU-side element count, with
// 2D grids past maxComputeWorkgroupsPerDimension; no readback, no host loops.
// Kernels dispatched with them rebuild the linear workgroup index with
// `grid_workgroup_index` (dispatchSnippet, shaders/primitives/dispatch.wgsl;
// equal to `linear_workgroup_index` of shaders/common/grid.wgsl whenever
// z = 1, that is below limit^2 workgroups) and skip indices past
// ceil(count / itemsPerWorkgroup).

import type { CountLike, GpuCount } from './count.ts';
import { DispatchRecords, RECORD_ARGS, maxWorkgroupsPerDimension, type PrimitiveOptions } from './dispatch-records.ts';

export interface IndirectArgsOptions extends Pick<PrimitiveOptions, 'maxWorkgroupsPerDimension'> {
  /** Elements one workgroup of the target kernel handles. */
  itemsPerWorkgroup: number;
}

export interface IndirectArgsEncodeArgs {
  /** Elements; a GpuCount's buffer needs COPY_SRC. */
  count: CountLike;
  /** Where the three u32 (x, y, z) go; the buffer needs COPY_DST (and INDIRECT to be used). */
  out: GpuCount;
}

export class IndirectArgs {
  private constructor(private readonly records: DispatchRecords) {}

  static async create(device: GPUDevice, options: IndirectArgsOptions): Promise<IndirectArgs> {
    const items = options.itemsPerWorkgroup;
    if (!Number.isInteger(items) || items < 1) throw new RangeError('itemsPerWorkgroup must be a positive integer');
    const records = await DispatchRecords.create(device, 'IndirectArgs', {
      chunk: items,
      wg: 1,
      levels: 1,
      capacity: 0xffffffff,
      maxWorkgroupsPerDimension: maxWorkgroupsPerDimension(device, options),
    });
    return new IndirectArgs(records);
  }

  /** Records: count copy, a one-thread pass, and the 12-byte copy to `out`. */
  encode(encoder: GPUCommandEncoder, args: IndirectArgsEncodeArgs): void {
    if (args.out.offset % 4 !== 0) throw new RangeError('out.offset must be a multiple of 4');
    this.records.encodeCount(encoder, args.count);
    const pass = encoder.beginComputePass({ label: 'IndirectArgs' });
    this.records.dispatchSetup(pass);
    pass.end();
    encoder.copyBufferToBuffer(this.records.params, RECORD_ARGS, args.out.buffer, args.out.offset, 12);
  }

  destroy(): void {
    this.records.destroy();
  }
}
