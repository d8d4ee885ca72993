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
import { chunkBlockId, chunkOfBlock } from '../../zfp/probe.ts';
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
    // the blocks the caps can read are in the level's resident chunks (the walk is sized by them, not the level)
    const per = pool.layout.chunkEdge / 4;
    const within = [...l.drawn, ...l.ghosts].map((c) => {
      const at = pool.chunkCoords(c);
      return { lo: at.map((g) => g * per), hi: at.map((g) => (g + 1) * per - 1) };
    });
    return {
      source: pool,
      clip: clipInLevel(clip, scale, offset),
      idOf: (b: number) => chunkBlockId(pool, b),
      owns: (b: number) => drawn.has(chunkOfBlock(pool, b).chunk),
      within,
      scale,
      offset,
    };
  });
}
