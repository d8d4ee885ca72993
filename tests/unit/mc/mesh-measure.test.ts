// measureSurface on meshes whose area, volume and closure are known by hand:
// a unit cube (area 6, volume 1) scaled per axis, the same cube in two pieces
// with their seam vertices duplicated (a store's chunks), a cube with a hole,
// and two pieces whose seam differs by one float32 step.
import { describe, expect, it } from 'vitest';
import { measureSurface, weldByPosition } from '../../../src/mc/mesh-measure.ts';
import { CUBE_FACES, unitCube } from './unit-cube.ts';

const FACES = CUBE_FACES;
const cube = unitCube;

/** Every triangle with its own three vertices (no sharing at all): welding by position must rebuild the edges. */
function soupOf(m: { positions: Float32Array; indices: Uint32Array }) {
  const positions = new Float32Array(3 * m.indices.length);
  m.indices.forEach((v, i) => positions.set(m.positions.subarray(3 * v, 3 * v + 3), 3 * i));
  return { positions, indices: new Uint32Array(m.indices.length).map((_, i) => i) };
}

describe('measureSurface', () => {
  it('a cube: area 6 and volume 1, scaled by the voxel size and moved by the origin', () => {
    const { positions, indices } = cube();
    const m = measureSurface(positions, indices);
    expect(m).toMatchObject({ triangles: 12, area: 6, closed: true, openEdges: 0 });
    expect(m.enclosedVolume).toBeCloseTo(1, 14);
    const s = measureSurface(positions, indices, { voxelSize: [2, 3, 0.5], origin: [10, -4, 7] });
    expect(s.area).toBeCloseTo(2 * (2 * 3 + 3 * 0.5 + 2 * 0.5), 12);
    expect(s.enclosedVolume).toBeCloseTo(3, 12);
  });

  it('wound the other way: the same volume', () => {
    const { positions, indices } = cube();
    for (let t = 0; t < indices.length; t += 3) [indices[t + 1], indices[t + 2]] = [indices[t + 2], indices[t + 1]];
    expect(measureSurface(positions, indices).enclosedVolume).toBeCloseTo(1, 12);
  });

  it('pieces that share no vertex index are welded by position', () => {
    const soup = soupOf(cube());
    expect(new Set(weldByPosition(soup.positions)).size).toBe(8);
    const m = measureSurface(soup.positions, soup.indices);
    expect(m.closed).toBe(true);
    expect(m.enclosedVolume).toBeCloseTo(1, 12);
  });

  it('a hole, or a seam one float32 step apart: open, with no volume', () => {
    const holed = cube(FACES.slice(1));
    const h = measureSurface(holed.positions, holed.indices);
    expect(h.closed).toBe(false);
    expect(h.enclosedVolume).toBeNull();
    expect(h.openEdges).toBe(4);
    expect(h.area).toBeCloseTo(5, 12);
    const soup = soupOf(cube());
    // the last face's copy of corner (0, 1, 1) (index 7, the 6th vertex of the face) moved by one ulp in y
    const v = 3 * (soup.indices.length - 1);
    soup.positions[v + 1] = Math.fround(1 + 2 ** -23);
    const seam = measureSurface(soup.positions, soup.indices);
    expect(seam.closed).toBe(false);
    expect(seam.openEdges).toBeGreaterThan(0);
  });

  it('a pinch and a zero-area triangle at a grid point keep a closed surface closed', () => {
    // two cubes sharing one edge (x = 1, y = 1): four triangles meet on it; plus a triangle (a, a, b)
    const a = cube();
    const b = cube();
    const positions = new Float32Array(48);
    positions.set(a.positions);
    for (let i = 0; i < 24; i += 3) positions.set([b.positions[i] + 1, b.positions[i + 1] + 1, b.positions[i + 2]], 24 + i);
    const indices = new Uint32Array([...a.indices, ...Array.from(b.indices, (i) => i + 8), 0, 0, 1]);
    const m = measureSurface(positions, indices);
    expect(m.closed).toBe(true);
    expect(m.enclosedVolume).toBeCloseTo(2, 12);
    expect(m.area).toBeCloseTo(12, 12);
  });

  it('no triangles: not closed; a bad index is refused', () => {
    expect(measureSurface(new Float32Array(0), new Uint32Array(0))).toMatchObject({ area: 0, closed: false, enclosedVolume: null });
    expect(() => measureSurface(new Float32Array(9), new Uint32Array([0, 1, 3]))).toThrow(/index 3 past 3 vertices/);
  });
});
