// The store's value at a point of the step on screen (a picked point): the
// trilinear value of the finest level of the step whose pool holds the
// cell's chunks, decoded from that pool as its surface decoded them (the
// surface a point lies on was made from that level's values). A frozen step
// (its pools let go) or a cell whose chunks no level holds has no value.
import type { IsosurfaceStats } from '../isosurface/types.ts';
import type { Isosurface } from '../isosurface/isosurface.ts';
import type { ChunkedVolume } from '../zfp/chunked-volume.ts';
import { chunkBlockId, type VolumeProbe } from '../zfp/probe.ts';
import type { ShownCut } from './stream/stream-types.ts';

export interface ShownValue {
  value: number;
  /** The level it was read from. */
  level: number;
}

/**
 * The value at `p` (level-0 voxel index coordinates) of the step `shown`,
 * whose level L lies at `levelOffsets[L]` (level-0 voxels) with voxels of
 * `levelScales[L]` level-0 voxels; null when no level of the step holds it.
 */
export async function shownValueAt(
  probe: VolumeProbe,
  shown: ShownCut<ChunkedVolume, IsosurfaceStats, Isosurface>,
  levelOffsets: readonly (readonly [number, number, number])[],
  levelScales: readonly (readonly [number, number, number])[],
  p: readonly [number, number, number],
): Promise<ShownValue | null> {
  if (shown.frozen) return null;
  // finest first: the step's levels are listed so; sorted anyway
  for (const l of [...shown.levels].sort((a, b) => a.level - b.level)) {
    const pool = l.volume;
    if (pool.isDestroyed) continue;
    const k = levelScales[l.level] ?? [2 ** l.level, 2 ** l.level, 2 ** l.level];
    const off = levelOffsets[l.level] ?? [0, 0, 0];
    const at = [0, 1, 2].map((a) => (p[a] - off[a]) / k[a]) as [number, number, number];
    // outside this level's voxels (a level placed apart by its translation): another level may hold it
    if (at.some((x, a) => x < -0.5 || x > pool.info.dims[a] - 0.5)) continue;
    const value = await probe.sample(pool, at, (b) => chunkBlockId(pool, b));
    if (value !== null) return { value, level: l.level };
  }
  return null;
}
