// The stream controller's GPU side: one ChunkedVolume (pool of compressed
// chunks + page table) per level and the one isosurface pipeline over it.
import type { GpuContext } from '../gpu/device.ts';
import { Isosurface } from '../isosurface/isosurface.ts';
import type { IsosurfaceStats } from '../isosurface/types.ts';
import { ChunkedVolume } from '../zfp/chunked-volume.ts';
import type { StreamGpu } from './stream-controller.ts';

export function chunkedGpu(gpu: GpuContext): StreamGpu<ChunkedVolume, IsosurfaceStats, Isosurface> {
  return {
    createVolume: (layout, poolChunks) =>
      ChunkedVolume.create(gpu, layout, { poolChunks: Math.min(poolChunks, ChunkedVolume.maxPoolChunks(gpu, layout)) }),
    createSurface: (volume, memoryBudgetBytes) => Isosurface.create(gpu, volume, { memoryBudgetBytes }),
  };
}
