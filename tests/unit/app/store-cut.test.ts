// The page's surface of a store refined by the view (src/app/store/store-cut.ts)
// when the cut on screen holds no surface (an isovalue outside every chunk in
// view, issue 36): the frame loop reads drawData and drawParts every frame,
// exports read the mesh, the slider reads block ranges; none of them may throw.
import { describe, expect, it } from 'vitest';
import { StoreCutIsosurface, type ShownCutOfPage } from '../../../src/app/store/store-cut.ts';
import type { ChunkStoreStream } from '../../../src/store/gpu-port.ts';

function fakeStream(): ChunkStoreStream {
  return {
    levels: [{ layout: { dims: [64, 64, 64] } }],
    store: { levelOffsets: [[0, 0, 0]], levelScales: [[1, 1, 1]] },
    onError: () => () => {},
  } as unknown as ChunkStoreStream;
}

const emptyCut = (iso: number): ShownCutOfPage =>
  ({ iso, step: 0, final: true, levels: [], cut: { levels: [], nodes: [] }, leaves: [[]] }) as unknown as ShownCutOfPage;

describe('StoreCutIsosurface with an empty cut', () => {
  it('draws nothing, reads an empty mesh and no block ranges, and counts no triangles', async () => {
    const s = new StoreCutIsosurface(
      fakeStream(),
      emptyCut(-5),
      [0, 1],
      async () => {},
      () => {},
    );
    expect(s.drawData).toBeUndefined();
    expect(s.drawParts()).toEqual([]);
    expect(s.stats.triangles).toBe(0);
    const mesh = await s.readMesh();
    expect(mesh.vertices.length).toBe(0);
    expect(mesh.indices.length).toBe(0);
    expect((await s.readBlockRanges()).length).toBe(0);
    const joined = await s.readPositions();
    expect(joined.indices.length).toBe(0);
    s.tint = true;
    expect(s.drawParts()).toEqual([]);
    s.showAgain(emptyCut(-6));
    expect(s.drawData).toBeUndefined();
    s.destroy();
  });
});
