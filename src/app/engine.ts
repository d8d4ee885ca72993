// What the page needs from the isosurface pipeline (src/isosurface/): the
// `Isosurface` class satisfies this; the page only talks to this interface.
import type { GpuContext } from '../gpu/device.ts';
import type { IsosurfaceDrawData, IsosurfaceStats, VolumeInfo } from '../isosurface/types.ts';
import type { ZfpGpuStream } from '../zfp/gpu-stream.ts';

export interface PageIsosurface {
  readonly info: VolumeInfo;
  /** What to draw now (the newest surface computed so far). */
  readonly drawData: IsosurfaceDrawData;
  /** Requests the surface at `iso`; newer requests replace older ones that have not started. */
  setIsovalue(iso: number): void;
  compute(iso: number): Promise<IsosurfaceStats>;
  onStats(listener: (stats: IsosurfaceStats) => void): unknown;
  onError(listener: (error: Error) => void): unknown;
  resetCache(): Promise<void> | void;
  setMemoryBudget(bytes: number): void;
  /** Packed vertex pairs of the current surface. */
  readVertices(): Promise<Uint32Array>;
  /** [min, max] per block. */
  readBlockRanges(): Promise<Float32Array>;
  destroy(): void;
}

export async function createIsosurface(gpu: GpuContext, stream: ZfpGpuStream): Promise<PageIsosurface> {
  const { CpuIsosurface } = await import('../render/testing/cpu-isosurface.ts');
  return CpuIsosurface.create(gpu, stream);
}
