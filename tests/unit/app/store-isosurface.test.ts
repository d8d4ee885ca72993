// The page's surface of a streamed store (src/app/store/store-isosurface.ts)
// when the step on screen holds no surface (an isovalue outside every chunk in
// view, issue 36): the frame loop reads drawData and drawParts every frame,
// exports read the mesh, the slider reads block ranges; none of them may throw.
import { describe, expect, it } from 'vitest';
import { StoreIsosurface, type ShownStep } from '../../../src/app/store/store-isosurface.ts';
import type { ChunkStoreStream } from '../../../src/store/gpu-port.ts';

let shown: ShownStep;

function fakeStream(): ChunkStoreStream {
  return {
    levels: [{ layout: { dims: [64, 64, 64] } }],
    store: { levelOffsets: [[0, 0, 0]], levelScales: [[1, 1, 1]] },
    onError: () => () => {},
    // the step on screen, held while it is read (an export)
    readShown: async <T>(read: (s: ShownStep) => Promise<T>) => read(shown),
  } as unknown as ChunkStoreStream;
}

const emptyCut = (iso: number): ShownStep => {
  shown = { iso, others: [], step: 0, final: true, levels: [], cut: { levels: [], nodes: [] }, leaves: [[]] } as unknown as ShownStep;
  return shown;
};

describe('StoreIsosurface with an empty cut', () => {
  it('draws nothing, reads an empty mesh and no block ranges, and counts no triangles', async () => {
    const s = new StoreIsosurface(
      fakeStream(),
      emptyCut(-5),
      [0, 1],
      async () => {},
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
