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
import { type CutLevel, viewCut } from '../../../src/store/view/cut.ts';
import { cameraForBox, cameraFromView, sceneRadiusOf } from '../../../src/store/view/camera.ts';
import { DEFAULT_VIEWPORT } from '../../../src/store/view/view-request.ts';
import { guessedSurfaceBytesPerChunk, residentChunkBytes } from '../../../src/store/level-state.ts';
import type { ChunkLevelLayout } from '../../../src/store/types.ts';

type V3 = [number, number, number];

function pyramid(n: number, edge: number, levels: number): CutLevel[] {
  return Array.from({ length: levels }, (_, L) => {
    const d = Math.ceil(n / 2 ** L);
    const g = Math.ceil(d / edge);
    return { dims: [d, d, d] as V3, chunkEdge: edge, chunkGrid: [g, g, g] as V3 };
  });
}

/** The stream's planned cost of one wanted 64^3 chunk at rate 8 before any surface (the cost model, level-state.ts). */
const LAYOUT_64_RATE_8 = { chunkEdge: 64, chunkBytes: 64 ** 3 } as ChunkLevelLayout;
const CHUNK_COST = residentChunkBytes(LAYOUT_64_RATE_8) + guessedSurfaceBytesPerChunk(LAYOUT_64_RATE_8);

describe('a binding budget goes to what the view frames first', () => {
  const levels = pyramid(2048, 64, 6);
  const voxelSize: V3 = [1, 1, 1];
  const boxes: [string, [number, number, number, number, number, number]][] = [
    ['the far corner (the one Fit looks at from +z)', [1792, 1792, 1792, 2047, 2047, 2047]],
    ['a box in the middle of a face', [896, 896, 1792, 1151, 1151, 2047]],
  ];
  /** The cut for the box's framing at `mb` MB (the view stream plans with 0.8 of it), and the level-0 chunks of the box it draws against those the unlimited cut draws. */
  function framedCut(box: (typeof boxes)[number][1], mb: number, focus = true) {
    const framed = cameraForBox(box, voxelSize, DEFAULT_VIEWPORT);
    const camera = cameraFromView(framed.state, DEFAULT_VIEWPORT, sceneRadiusOf(box, voxelSize));
    if (!focus) delete (camera as { focus?: unknown }).focus;
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
    const budgetBytes = (mb << 20) * 0.8;
    const free = viewCut({ ...input, budgetBytes: Infinity });
    const cut = viewCut({ ...input, budgetBytes });
    const inBox = (n: { level: number; coords: V3 }) => {
      const e = 64 * 2 ** n.level;
      return n.coords.every((c, a) => c * e >= box[a] && (c + 1) * e <= box[a + 3] + 1);
    };
    const wanted = free.nodes.filter((n) => n.level === 0 && inBox(n)).map((n) => n.chunk);
    const got = new Set(cut.nodes.filter((n) => n.level === 0).map((n) => n.chunk));
    const boxLeaves = cut.nodes.filter((n) => n.level <= 2 && inBox(n));
    return { cut, free, budgetBytes, wanted, drawn: wanted.filter((c) => got.has(c)), boxLeaves };
  }

  for (const [name, box] of boxes) {
    it(`${name}, 1 GB: the whole framed box at level 0 (where it needs it), within the budget`, () => {
      const r = framedCut(box, 1024);
      expect(r.free.bytes, 'the budget binds here').toBeGreaterThan(r.budgetBytes);
      expect(r.cut.bytes).toBeLessThanOrEqual(r.budgetBytes);
      expect(r.wanted.length).toBe(64);
      expect(r.drawn.length, 'level-0 chunks of the framed box drawn').toBe(64);
    });
  }

  it('the far corner at 256 MB: most of the framed box at level 0 and none of it coarser than level 1; by error alone it was a quarter', () => {
    const box = boxes[0][1];
    const r = framedCut(box, 256);
    expect(r.cut.bytes).toBeLessThanOrEqual(r.budgetBytes);
    expect(r.drawn.length).toBeGreaterThanOrEqual(32);
    expect(r.boxLeaves.every((n) => n.level <= 1)).toBe(true);
    // the same cut without a focus (the rule before): the budget went around and behind the box
    const errorOnly = framedCut(box, 256, false);
    expect(errorOnly.drawn.length).toBeLessThan(r.drawn.length);
  });
});
