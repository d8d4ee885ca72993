// Active blocks (DESIGN.md step 1): per-block value ranges from the decoder
// at load, widened once to each block's 27-block neighbourhood on the GPU;
// per isovalue one compare per block, a scan and an ID compaction give the
// active list I_active (raster order) and its length in the counters.
import { dispatchLinear } from '../gpu/dispatch.ts';
import { readF32 } from '../gpu/buffers.ts';
import type { ExclusiveScan } from '../primitives/scan.ts';
import type { StreamCompactIds } from '../primitives/compact.ts';
import type { ZfpDecoder } from '../zfp/decoder.ts';
import type { ZfpGpuStream } from '../zfp/gpu-stream.ts';
import type { Counters } from './counters.ts';
import { bindGroup, bindGroupLayout, computePipeline, storageBuffer } from './gpu-util.ts';
import { isosurfaceWgsl } from './wgsl.ts';

export interface ActiveBlocksParts {
  stream: ZfpGpuStream;
  decoder: ZfpDecoder;
  /** VolumeParams uniform (common.wgsl). */
  volume: GPUBuffer;
  counters: Counters;
  scan: ExclusiveScan;
  compactIds: StreamCompactIds;
  maxWorkgroupsPerDimension: number;
}

export class ActiveBlocks {
  /** 2 f32 (min, max) per block over its voxels inside the volume. */
  readonly blockRanges: GPUBuffer;
  /** 2 f32 per block: min and max over the block and its 26 neighbours. */
  readonly neighbourhoodRanges: GPUBuffer;
  /** u32 per block: 1 if active for the current isovalue. */
  readonly activeMask: GPUBuffer;
  readonly activeOffsets: GPUBuffer;
  /** Active block ids, ascending; the first counters[active] entries are valid. */
  readonly activeIds: GPUBuffer;
  private readonly maskGroup: GPUBindGroup;

  private constructor(
    private readonly device: GPUDevice,
    private readonly parts: ActiveBlocksParts,
    private readonly maskPipeline: GPUComputePipeline,
    maskLayout: GPUBindGroupLayout,
  ) {
    const blocks = parts.stream.info.blockCount;
    this.blockRanges = parts.decoder.computeBlockRanges(parts.stream);
    this.neighbourhoodRanges = storageBuffer(device, 'Isosurface.neighbourhoodRanges', blocks * 8);
    this.activeMask = storageBuffer(device, 'Isosurface.activeMask', blocks * 4);
    this.activeOffsets = storageBuffer(device, 'Isosurface.activeOffsets', blocks * 4);
    this.activeIds = storageBuffer(device, 'Isosurface.activeIds', blocks * 4);
    this.maskGroup = bindGroup(device, 'Isosurface.activeMask.bindGroup', maskLayout, [parts.volume, this.neighbourhoodRanges, this.activeMask]);
  }

  /** Computes the block ranges and their neighbourhood ranges (one submission). */
  static async create(device: GPUDevice, parts: ActiveBlocksParts): Promise<ActiveBlocks> {
    const layout = bindGroupLayout(device, 'Isosurface.activeBlocks.layout', ['uniform', 'read', 'rw']);
    const constants = { MAX_WG_PER_DIM: parts.maxWorkgroupsPerDimension };
    const [neighbourhood, mask] = await Promise.all([
      computePipeline(device, 'Isosurface.neighbourhoodRange', isosurfaceWgsl.activeBlocks, 'neighbourhood_range', [layout], constants),
      computePipeline(device, 'Isosurface.markActiveBlocks', isosurfaceWgsl.activeBlocks, 'mark_active_blocks', [layout], constants),
    ]);
    const active = new ActiveBlocks(device, parts, mask, layout);
    const encoder = device.createCommandEncoder({ label: 'Isosurface.neighbourhoodRanges' });
    const pass = encoder.beginComputePass({ label: 'Isosurface.neighbourhoodRanges' });
    pass.setPipeline(neighbourhood);
    pass.setBindGroup(0, bindGroup(device, 'Isosurface.neighbourhoodRange.bindGroup', layout, [parts.volume, active.blockRanges, active.neighbourhoodRanges]));
    dispatchLinear(pass, Math.ceil(parts.stream.info.blockCount / 64), parts.maxWorkgroupsPerDimension);
    pass.end();
    device.queue.submit([encoder.finish()]);
    return active;
  }

  get blockCount(): number {
    return this.parts.stream.info.blockCount;
  }

  /** Records the active mask, its scan (total -> counters.active) and the active list. */
  encode(encoder: GPUCommandEncoder, timestampWrites?: GPUComputePassTimestampWrites): void {
    const { counters, scan, compactIds, maxWorkgroupsPerDimension } = this.parts;
    const pass = encoder.beginComputePass({ label: 'Isosurface.activeMask', timestampWrites });
    pass.setPipeline(this.maskPipeline);
    pass.setBindGroup(0, this.maskGroup);
    dispatchLinear(pass, Math.ceil(this.blockCount / 64), maxWorkgroupsPerDimension);
    pass.end();
    const all = counters.count('blocks');
    scan.encode(encoder, { input: this.activeMask, output: this.activeOffsets, count: all, totalOut: counters.count('active') });
    compactIds.encode(encoder, { mask: this.activeMask, offsets: this.activeOffsets, output: this.activeIds, count: all });
  }

  /** The per-block (min, max) ranges, 2 f32 per block in raster block order (waits for the GPU). */
  async readBlockRanges(): Promise<Float32Array> {
    return readF32(this.device, this.blockRanges);
  }

  /** Bytes held (fixed per volume). */
  get byteSize(): number {
    return this.blockRanges.size + this.neighbourhoodRanges.size + this.activeMask.size + this.activeOffsets.size + this.activeIds.size;
  }

  destroy(): void {
    for (const b of [this.blockRanges, this.neighbourhoodRanges, this.activeMask, this.activeOffsets, this.activeIds]) b.destroy();
  }
}
