// A store's caps (render/cap-layer.ts pieces): where the page's clip cuts
// the step on screen open, a piece per level of the step, decoded from that
// level's pool (the blocks of its resident chunks, named by slot) and drawn
// only over the cells of the chunks that level draws, so the levels' caps
// meet without overlapping. The stream fetches the chunks along the cut
// while caps are on (StreamLevels.capNeeds). A step released to its copies
// has no pools: no caps.
import { type Clip, clipInLevel } from '../../core/clip.ts';
import type { CapPiece } from '../../render/cap-layer.ts';
import type { ZfpStore } from '../../store/zarr/store.ts';
import { chunkBlockId } from '../../zfp/probe.ts';
import type { IsosurfaceStats } from '../../isosurface/types.ts';
import type { Isosurface } from '../../isosurface/isosurface.ts';
import type { ShownCut } from '../../store/stream/stream-types.ts';
import type { ChunkedVolume } from '../../zfp/chunked-volume.ts';

type ShownStep = ShownCut<ChunkedVolume, IsosurfaceStats, Isosurface>;

export function storeCapPieces(store: Pick<ZfpStore, 'levelOffsets' | 'levelScales'>, shown: ShownStep, clip: Clip): CapPiece[] {
  if (shown.frozen) return [];
  return shown.levels.map((l) => {
    const pool = l.volume;
    const scale = store.levelScales[l.level] ?? [2 ** l.level, 2 ** l.level, 2 ** l.level];
    const offset = store.levelOffsets[l.level] ?? [0, 0, 0];
    const drawn = new Set(l.drawn);
    const { chunkGrid, chunkEdge } = pool.layout;
    const grid = pool.info.blockGrid;
    const per = chunkEdge / 4;
    const chunkOf = (b: number) => {
      const bx = b % grid[0];
      const by = Math.floor(b / grid[0]) % grid[1];
      const bz = Math.floor(b / (grid[0] * grid[1]));
      return Math.floor(bx / per) + chunkGrid[0] * (Math.floor(by / per) + chunkGrid[1] * Math.floor(bz / per));
    };
    return {
      source: pool,
      clip: clipInLevel(clip, scale, offset),
      idOf: (b: number) => chunkBlockId(pool, b),
      owns: (b: number) => drawn.has(chunkOf(b)),
      scale,
      offset,
    };
  });
}
