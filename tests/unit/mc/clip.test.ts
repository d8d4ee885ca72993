// clipMesh and regionClipped on shapes known by hand: a unit cube's surface
// cut by the plane x >= 0.5 keeps the face x = 1 and half of four faces
// (area 3), split triangles keep their winding and share their cut vertices;
// a box of whole cells keeps the triangles whose centroid lies in it; a
// region wholly outside the box or behind the plane is clipped.
import { describe, expect, it } from 'vitest';
import { boxEntryFace, capPolygons, clipMesh, clipPlanes, nearestOnAxis, regionClipped } from '../../../src/core/clip.ts';
import { measureSurface } from '../../../src/mc/mesh-measure.ts';
import { unitCube } from './unit-cube.ts';

const cube = () => unitCube();

describe('clipMesh', () => {
  it('a plane keeps the positive side, split where it crosses', () => {
    const { positions, indices } = cube();
    const cut = clipMesh(positions, indices, { plane: { normal: [1, 0, 0], d: 0.5 } });
    const m = measureSurface(cut.positions, cut.indices);
    expect(m.area).toBeCloseTo(3, 12);
    // the cut is an open square rim of 4 edges, each split edge welded once
    expect(m.closed).toBe(false);
    expect(m.openEdges).toBe(8);
    for (const v of cut.indices) expect(cut.positions[3 * v]).toBeGreaterThanOrEqual(0.5);
    // winding kept: the kept half-cube's volume with the cut closed by hand would be 0.5; the signed
    // area vector of the kept part points along +x by the missing face's area (1)
    let sx = 0;
    for (let t = 0; t < cut.indices.length; t += 3) {
      const [a, b, c] = [0, 1, 2].map((k) => 3 * cut.indices[t + k]);
      const u = [1, 2].map((k) => cut.positions[b + k] - cut.positions[a + k]);
      const v = [1, 2].map((k) => cut.positions[c + k] - cut.positions[a + k]);
      sx += 0.5 * (u[0] * v[1] - u[1] * v[0]);
    }
    expect(sx).toBeCloseTo(1, 12);
    expect(clipMesh(positions, indices, { plane: { normal: [1, 0, 0], d: 2 } }).indices.length).toBe(0);
    expect(clipMesh(positions, indices, { plane: { normal: [1, 0, 0], d: -1 } }).indices).toEqual(indices);
  });

  it('a box keeps the triangles of its cells', () => {
    // two triangles, centroids in cells (0,0,0) and (2,0,0)
    const positions = new Float32Array([0.2, 0.2, 0.5, 0.8, 0.2, 0.5, 0.5, 0.8, 0.5, 2.2, 0.2, 0.5, 2.8, 0.2, 0.5, 2.5, 0.8, 0.5]);
    const indices = new Uint32Array([0, 1, 2, 3, 4, 5]);
    expect(Array.from(clipMesh(positions, indices, { box: [0, 0, 0, 2, 1, 1] }).indices)).toEqual([0, 1, 2]);
    expect(Array.from(clipMesh(positions, indices, { box: [1, 0, 0, 3, 1, 1] }).indices)).toEqual([3, 4, 5]);
    expect(Array.from(clipMesh(positions, indices, { box: [0, 0, 0, 3, 1, 1] }).indices)).toEqual([0, 1, 2, 3, 4, 5]);
  });
});

describe('regionClipped', () => {
  it('outside the box or behind the plane', () => {
    expect(regionClipped([0, 0, 0], [64, 64, 64], { box: [64, 0, 0, 128, 10, 10] })).toBe(true);
    expect(regionClipped([0, 0, 0], [64, 64, 64], { box: [63, 0, 0, 128, 10, 10] })).toBe(false);
    expect(regionClipped([0, 0, 0], [64, 64, 64], { plane: { normal: [-1, 0, 0], d: -10 } })).toBe(false);
    expect(regionClipped([0, 0, 0], [64, 64, 64], { plane: { normal: [1, 1, 0], d: 129 } })).toBe(true);
    expect(regionClipped([0, 0, 0], [64, 64, 64], undefined)).toBe(false);
    expect(clipPlanes({ box: [1, 2, 3, 4, 5, 6] })).toHaveLength(6);
  });
});

describe('clip box dragging and caps geometry', () => {
  it('the face a ray enters first, and the point of an axis nearest a ray', () => {
    const box = [0, 0, 0, 10, 10, 10] as const;
    expect(boxEntryFace(box, [5, 5, 20], [0, 0, -1])).toEqual({ axis: 2, side: 1, point: [5, 5, 10] });
    expect(boxEntryFace(box, [-5, 2, 3], [1, 0.1, 0])).toMatchObject({ axis: 0, side: 0 });
    expect(boxEntryFace(box, [-5, 20, 3], [1, 0, 0])).toBeNull(); // misses
    expect(boxEntryFace(box, [5, 5, 5], [1, 0, 0])).toBeNull(); // starts inside
    // the x axis through (10, 5, 5) and a ray down through x = 14: nearest at s = 4
    expect(nearestOnAxis([10, 5, 5], 0, [14, 5, 30], [0, 0, -1])).toBeCloseTo(4, 12);
    expect(nearestOnAxis([10, 5, 5], 0, [14, 9, 30], [0, 0.1, -1])).toBeCloseTo(4, 12);
  });

  it('cap polygons: a box face, and a plane cut by the box and kept by the others', () => {
    const caps = capPolygons({ box: [2, 0, 0, 8, 10, 10] }, [11, 11, 11]);
    expect(caps).toHaveLength(6);
    const xLow = caps.find((c) => c.plane[0] === 1)!;
    expect(xLow.corners).toHaveLength(4);
    for (const p of xLow.corners) expect(p[0]).toBeCloseTo(2, 12);
    // a plane x + y >= 10 in the box [0, 10]^3: a rectangle of side 10 by 10 sqrt 2
    const [diag] = capPolygons({ plane: { normal: [1, 1, 0], d: 10 } }, [11, 11, 11]);
    expect(diag.corners).toHaveLength(4);
    let area = 0;
    for (let i = 1; i + 1 < diag.corners.length; i++) {
      const [a, b, c] = [diag.corners[0], diag.corners[i], diag.corners[i + 1]];
      const u = b.map((v, k) => v - a[k]);
      const w = c.map((v, k) => v - a[k]);
      area += 0.5 * Math.hypot(u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]);
    }
    expect(area).toBeCloseTo(100 * Math.SQRT2, 9);
    // the same plane with the box x <= 5: only the part x in [0, 5] stays
    const [half] = capPolygons({ plane: { normal: [1, 1, 0], d: 10 }, box: [0, 0, 0, 5, 10, 10] }, [11, 11, 11]).filter(
      (c) => c.plane[1] === 1 && c.plane[0] === 1,
    );
    for (const p of half.corners) expect(p[0]).toBeLessThanOrEqual(5 + 1e-9);
  });
});
