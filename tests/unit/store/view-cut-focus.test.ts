// Where the view cut spends a budget that binds (issue 36): on what the view
// frames first. A 2048^3 store in 64^3 chunks (levels 0..5, the converter's
// pyramid of a generated volume), a camera framing a 256^3 corner the way
// `extract --view-box` and the page's Fit do, at the cost per wanted chunk
// the view stream plans with (rate 8) and the budget of 256 MB: the framed
// region is drawn at level 0 where its voxels project to more than the
// tolerance, and coarser around and behind it. The framing and projection
// are the page's (cut.ts's cameraForBox is checked against the page's
// ArcballCamera in view-cut.test.ts); what counts as "framed" is the box
// given, computed here from the level-0 boxes of the leaves.
import { describe, expect, it } from 'vitest';
import { type CutLevel, cameraForBox, cameraFromView, sceneRadiusOf, viewCut } from '../../../src/store/view/cut.ts';
import { DEFAULT_VIEWPORT } from '../../../src/store/view/view-request.ts';

type V3 = [number, number, number];

function pyramid(n: number, edge: number, levels: number): CutLevel[] {
  return Array.from({ length: levels }, (_, L) => {
    const d = Math.ceil(n / 2 ** L);
    const g = Math.ceil(d / edge);
    return { dims: [d, d, d] as V3, chunkEdge: edge, chunkGrid: [g, g, g] as V3 };
  });
}

/** The view stream's planned cost of one wanted 64^3 chunk at rate 8 (view-stream.ts #chunkCost before any surface). */
const CHUNK_COST = 64 ** 3 + (48 * 4096 + 32) + 4096 * 0.5 * 384;

describe('a binding budget goes to what the view frames first', () => {
  const levels = pyramid(2048, 64, 6);
  const voxelSize: V3 = [1, 1, 1];
  for (const [name, box] of [
    ['the far corner (the one Fit looks at from +z)', [1792, 1792, 1792, 2047, 2047, 2047]],
    ['a box in the middle of a face', [896, 896, 1792, 1151, 1151, 2047]],
  ] as [string, [number, number, number, number, number, number]][]) {
    it(`${name}, 256 MB: level 0 where the framed box needs it, within the budget`, () => {
      const framed = cameraForBox(box, voxelSize, DEFAULT_VIEWPORT);
      const camera = cameraFromView(framed.state, DEFAULT_VIEWPORT, sceneRadiusOf(box, voxelSize));
      const input = {
        levels,
        voxelSize,
        camera,
        tolerancePx: 1.5,
        finest: 0,
        coarsest: levels.length - 1,
        needs: () => () => true,
        chunkBytes: () => CHUNK_COST,
      };
      const free = viewCut({ ...input, budgetBytes: Infinity });
      const budgetBytes = (256 << 20) * 0.8;
      const cut = viewCut({ ...input, budgetBytes });
      expect(cut.bytes).toBeLessThanOrEqual(budgetBytes);
      expect(free.bytes, 'the budget binds here').toBeGreaterThan(budgetBytes);
      const inBox = (n: { level: number; coords: V3 }) => {
        const e = 64 * 2 ** n.level;
        return n.coords.every((c, a) => c * e >= box[a] && (c + 1) * e <= box[a + 3] + 1);
      };
      // the level-0 chunks the framed box holds in the unlimited cut: all of them in the budgeted one
      const wanted = free.nodes.filter((n) => n.level === 0 && inBox(n)).map((n) => n.chunk);
      expect(wanted.length).toBeGreaterThan(8);
      const got = new Set(cut.nodes.filter((n) => n.level === 0).map((n) => n.chunk));
      expect(
        wanted.filter((c) => !got.has(c)),
        'level-0 chunks of the framed box left coarser',
      ).toEqual([]);
    });
  }
});
