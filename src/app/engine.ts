// What the page needs from the isosurface pipeline (src/isosurface/): the
// `Isosurface` class satisfies this; the page only talks to this interface.
import type { SurfacePart } from '../render/surface-layer.ts';
import type { RayLevel, RayRegions } from '../render/ray-layer.ts';
import type { GpuContext } from '../gpu/device.ts';
import { Isosurface } from '../isosurface/isosurface.ts';
import type { IsosurfaceDrawData, IsosurfaceOptions, IsosurfaceStats, SurfaceMesh, VolumeInfo } from '../isosurface/types.ts';
import type { ZfpGpuStream } from '../zfp/gpu-stream.ts';
import type { SurfaceSnapshot } from '../isosurface/snapshot.ts';
import type { VolumeProbe } from '../zfp/probe.ts';
import type { Clip } from '../core/clip.ts';
import type { CapPiece } from '../render/cap-layer.ts';

/** A store's step as the page's rays draw it (StoreIsosurface.rayLevels). */
export interface PageRayLevels {
  levels: RayLevel[];
  extent: readonly [number, number, number];
  iso: number;
  regions: RayRegions;
  /** Whether the step is its plan's last (the rays then read their depth to refine it: guideRays). */
  final: boolean;
  /** The step's identity (the same while its levels are). */
  step: unknown;
}

export interface PageIsosurface {
  readonly info: VolumeInfo;
  /** What to draw now (the newest surface computed so far); none for a surface of pieces that holds none (drawParts). */
  readonly drawData: IsosurfaceDrawData | undefined;
  /** Requests the surface at `iso`; newer requests replace older ones that have not started. */
  setIsovalue(iso: number): void;
  compute(iso: number): Promise<IsosurfaceStats>;
  onStats(listener: (stats: IsosurfaceStats) => void): unknown;
  onError(listener: (error: Error) => void): unknown;
  /** After each computation's submission: a frame drawn from then on shows that surface. */
  onSubmit(listener: (iso: number) => void): unknown;
  resetCache(): Promise<void> | void;
  setMemoryBudget(bytes: number): void;
  /** The current surface as an indexed mesh (welded vertices, indices). */
  readMesh(): Promise<SurfaceMesh>;
  /** In-core surfaces (the page's several surfaces keep theirs as copies): a copy this surface fills with copyInto. */
  newCopy?(): SurfaceSnapshot;
  /** Copies the surface computed last (after compute() resolved, before the next request). */
  copyInto?(copy: SurfaceSnapshot): void;
  /** Bytes the cache and vertices hold now. */
  readonly budgetedBytes?: number;
  /** [min, max] per block. */
  readBlockRanges(): Promise<Float32Array>;
  /** A surface of several pieces (a store refined by the view: one per level): what the layer draws instead of drawData. */
  drawParts?(): SurfacePart[];
  /** A store: its step on screen for the ray caster, when its live caches hold it (StoreIsosurface.rayLevels). */
  rayLevels?(): PageRayLevels | undefined;
  /** A store: where an image of its final step's rays found the surface, to refine there (StoreIsosurface.guideRays); whether it asked. */
  guideRays?(seenHits: { hits: Float64Array; dirs: Float64Array }): boolean;
  /** A store: whether the page draws it by rays (its live caches are then kept whole). */
  setRaysWanted?(on: boolean): void;
  /** Such a surface's mesh as one, in its voxel index space (voxel (i, j, k) at (i, j, k)), for exports; `iso`: one of its other surfaces. */
  readPositions?(iso?: number): Promise<{ positions: Float32Array; indices: Uint32Array }>;
  /** A store's stream: the other isovalues (the page's other surfaces) every step draws with the next setIsovalue's. */
  setOtherIsovalues?(isos: readonly number[]): void;
  /** Such a surface's pieces at one of the isovalues of the step on screen (none: not drawn by it). */
  partsAt?(iso: number): SurfacePart[] | undefined;
  /** A store's value at a point (level-0 voxels) of the step on screen, and the level it came from; null where no level holds it. */
  valueAt?(p: readonly [number, number, number], probe: VolumeProbe): Promise<{ value: number; level: number } | null>;
  /** A store's caps of a clip on the step on screen: a piece per level (CapLayer.setPieces). */
  capPieces?(clip: Clip): CapPiece[];
  /** Triangles of the step on screen at one of its isovalues. */
  trianglesAt?(iso: number): number | undefined;
  destroy(): void;
}

export function createIsosurface(gpu: GpuContext, stream: ZfpGpuStream, options: IsosurfaceOptions = {}): Promise<PageIsosurface> {
  return Isosurface.create(gpu, stream, options);
}
