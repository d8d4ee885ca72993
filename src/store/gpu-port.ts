// The store stream's GPU side: one ChunkedVolume (pool of compressed
// chunks + page table) per level and the one isosurface pipeline over it,
// all made on a metered view of the device, so what the stream holds on the
// GPU is counted where it is made (src/gpu/memory-meter.ts).
import type { GpuContext } from '../gpu/device.ts';
import { GpuMemoryMeter, meteredGpu } from '../gpu/memory-meter.ts';
import { Isosurface } from '../isosurface/isosurface.ts';
import type { IsosurfaceStats } from '../isosurface/types.ts';
import { ChunkedVolume } from '../zfp/chunked-volume.ts';
import { encoderFor, type ZfpEncoder } from '../zfp/encoder.ts';
import { maxShardBytesFor } from '../zfp/gpu-stream.ts';
import type { ChunkFetcher } from './fetch/chunk-fetcher.ts';
import type { LearntRanges } from './learnt-ranges.ts';
import { LevelStream } from './stream/level-stream.ts';
import type { StoreStream } from './stream/store-stream.ts';
import type { StreamGpu } from './stream-port.ts';
import type { ZfpStore } from './zarr/open-store.ts';

/** The store stream over real GPU pools (ChunkedVolume) and surfaces (Isosurface). */
export type ChunkStoreStream = StoreStream<ChunkedVolume, IsosurfaceStats, Isosurface>;

export interface ChunkedStreamGpu extends StreamGpu<ChunkedVolume, IsosurfaceStats, Isosurface> {
  readonly meter: GpuMemoryMeter;
}

/**
 * The real GPU side. `cacheOnly`: surfaces that make no triangles, only
 * their caches (a stream the ray caster draws: no vertex memory). `budgetMeter`: the meter of the budget the stream holds
 * against (a page's GpuBudget counts every store's buffers), the parent of
 * the port's own meter. `encoder` (made on the same device) encodes the
 * bricks of stores of lossless chunks into their slots; zfp stores need none.
 */
export function chunkedGpu(gpu: GpuContext, budgetMeter?: GpuMemoryMeter, encoder?: ZfpEncoder, cacheOnly = false): ChunkedStreamGpu {
  const meter = new GpuMemoryMeter(budgetMeter);
  const view = meteredGpu(gpu, meter).gpu;
  const maxShardBytes = maxShardBytesFor(gpu.device);
  return {
    meter,
    cacheOnly,
    get allocatedBytes() {
      return meter.bytes;
    },
    poolBytesFor: (layout, poolChunks) => ChunkedVolume.bytesFor(layout, poolChunks, maxShardBytes),
    createVolume: (layout, poolChunks) =>
      ChunkedVolume.create(view, layout, { poolChunks: Math.min(poolChunks, ChunkedVolume.maxPoolChunks(view, layout)), encoder }),
    createSurface: (volume, memoryBudgetBytes) => Isosurface.create(view, volume, { memoryBudgetBytes, cacheOnly }),
  };
}

/** The encoder of a store of lossless chunks (float32 pipeline compiled), or undefined for a zfp store. */
export async function storeEncoder(gpu: GpuContext, store: ZfpStore): Promise<ZfpEncoder | undefined> {
  return store.source ? encoderFor(gpu.device) : undefined;
}

/** The level-by-level stream over real GPU pools and surfaces, its port's meter counting what it holds. */
export async function createChunkStream(
  store: ZfpStore,
  fetcher: ChunkFetcher,
  gpu: GpuContext | ChunkedStreamGpu,
  budgetBytes: number,
  options: { learnt?: LearntRanges } = {},
): Promise<LevelStream<ChunkedVolume, IsosurfaceStats, Isosurface>> {
  const port = 'meter' in gpu ? gpu : chunkedGpu(gpu, undefined, await storeEncoder(gpu, store));
  return LevelStream.create<ChunkedVolume, IsosurfaceStats, Isosurface>(store, fetcher, port, budgetBytes, options);
}
