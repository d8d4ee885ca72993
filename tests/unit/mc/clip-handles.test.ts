// The clip handles' geometry (src/core/clip-handles.ts): projection to
// pixels against gl-matrix, picking, the nearest point of a line to a ray,
// the knob on its sphere and the plane between voxels and world units, each
// against cases worked by hand.
import { mat4, vec4 } from 'gl-matrix';
import { describe, expect, test } from 'vitest';
import {
  boxFaceCentre,
  knobDirection,
  knobIsFar,
  nearestHandle,
  nearestOnLine,
  planeCentre,
  planeFromWorld,
  planeToWorld,
  projectToPixels,
} from '../../../src/core/clip-handles.ts';
import { freePlanePolygon, nearestOnAxis } from '../../../src/core/clip.ts';
import { ArcballCamera } from '../../../src/render/camera.ts';

describe('handles on screen', () => {
  test('projectToPixels is the view-projection followed by the viewport (gl-matrix)', () => {
    const cam = new ArcballCamera();
    cam.fit({ min: [0, 0, 0], max: [10, 20, 30] }, 'y');
    cam.aspect = 640 / 480;
    const vp = cam.viewProjection(mat4.create());
    const out = [0, 0];
    for (const p of [
      [5, 10, 15],
      [0, 0, 0],
      [10, 20, 30],
      [3, 17, 2],
    ]) {
      const c = vec4.transformMat4(vec4.create(), [p[0], p[1], p[2], 1], vp);
      expect(projectToPixels(vp, p, 640, 480, out)).toBe(true);
      // gl-matrix works in float32
      expect(out[0]).toBeCloseTo(((c[0] / c[3] + 1) / 2) * 640, 3);
      expect(out[1]).toBeCloseTo(((1 - c[1] / c[3]) / 2) * 480, 3);
    }
    // the volume's centre is at the middle of the canvas; a point behind the eye has no place
    projectToPixels(vp, [5, 10, 15], 640, 480, out);
    expect(out[0]).toBeCloseTo(320, 3);
    expect(out[1]).toBeCloseTo(240, 3);
    const eye = cam.eyePosition();
    const behind = [0, 1, 2].map((a) => 2 * eye[a] - [5, 10, 15][a]); // the centre mirrored through the eye
    expect(projectToPixels(vp, behind, 640, 480, out)).toBe(false);
  });

  test('nearestHandle takes the closest within the radius, the first of equals, never one off screen', () => {
    const xy = [10, 10, 20, 10, Number.NaN, Number.NaN, 100, 100];
    expect(nearestHandle(xy, 4, 14, 10, 5)).toBe(0);
    expect(nearestHandle(xy, 4, 16, 10, 5)).toBe(1);
    expect(nearestHandle(xy, 4, 15, 10, 5)).toBe(0);
    expect(nearestHandle(xy, 4, 50, 50, 5)).toBe(-1);
    expect(nearestHandle(xy, 4, 103, 104, 5)).toBe(3); // exactly on the radius
    expect(nearestHandle(xy, 3, 103, 104, 5)).toBe(-1); // only the first three counted
  });

  test('boxFaceCentre: the face at its coordinate, the middle of the others', () => {
    expect(boxFaceCentre([0, 2, 4, 10, 12, 20], 0, 0)).toEqual([0, 7, 12]);
    expect(boxFaceCentre([0, 2, 4, 10, 12, 20], 1, 1)).toEqual([5, 12, 12]);
    expect(boxFaceCentre([0, 2, 4, 10, 12, 20], 2, 1)).toEqual([5, 7, 20]);
  });
});

describe('dragging', () => {
  test('nearestOnLine: the line point nearest a ray', () => {
    expect(nearestOnLine([0, 0, 0], [1, 0, 0], [3, 5, 0], [0, -1, 0])).toBeCloseTo(3, 12);
    expect(nearestOnLine([0, 0, 0], [1, 0, 0], [2, 1, 5], [0, 0, -7])).toBeCloseTo(2, 12);
    // a diagonal line through (1, 1, 0): the ray down through (4, 4, .) passes 3 sqrt 2 along it
    const e = [Math.SQRT1_2, Math.SQRT1_2, 0];
    expect(nearestOnLine([1, 1, 0], e, [4, 4, 9], [0, 0, -1])).toBeCloseTo(3 * Math.SQRT2, 12);
    // parallel: no direction to follow
    expect(nearestOnLine([0, 0, 0], [0, 0, 1], [3, 1, 9], [0, 0, -2])).toBeNaN();
    // along an axis it is nearestOnAxis (the box's face drag)
    const p = [3, 4, 5],
      o = [20, -7, 30],
      d = [-1, 0.5, -2];
    expect(nearestOnLine(p, [0, 1, 0], o, d)).toBeCloseTo(nearestOnAxis(p, 1, o, d), 12);
  });

  test('knobDirection: where the ray meets the sphere, near or far side; the nearest point when it misses', () => {
    const near = knobDirection([0, 0, 0], 2, [1, 0, 10], [0, 0, -1], false)!;
    [0.5, 0, Math.sqrt(3) / 2].forEach((v, a) => expect(near[a]).toBeCloseTo(v, 12));
    const far = knobDirection([0, 0, 0], 2, [1, 0, 10], [0, 0, -1], true)!;
    [0.5, 0, -Math.sqrt(3) / 2].forEach((v, a) => expect(far[a]).toBeCloseTo(v, 12));
    // off-centre sphere, a ray that misses: toward the ray's closest point (5, 0, 0) from (1, 0, 0)
    const miss = knobDirection([1, 0, 0], 2, [5, 0, 10], [0, 0, -3], false)!;
    [1, 0, 0].forEach((v, a) => expect(miss[a]).toBeCloseTo(v, 12));
    // a ray through the knob (c + r n) gives n back
    const n = [2 / 3, -1 / 3, 2 / 3];
    const knob = n.map((v, a) => [4, 5, 6][a] + 3 * v);
    const eye = [20, 30, 40];
    const dir = knob.map((v, a) => v - eye[a]);
    const back = knobDirection([4, 5, 6], 3, eye, dir, knobIsFar(n, dir))!;
    n.forEach((v, a) => expect(back[a]).toBeCloseTo(v, 12));
    expect(knobIsFar([0, 0, 1], [0, 0, -1])).toBe(false);
    expect(knobIsFar([0, 0, -1], [0, 0, -1])).toBe(true);
  });
});

describe('the plane in world units', () => {
  const voxelSize = [2, 1, 0.5];
  const origin = [1, -2, 3];
  const toWorld = (x: number[]) => x.map((v, a) => (v + origin[a]) * voxelSize[a]);
  const plane = { normal: [1 / 3, 2 / 3, 2 / 3] as [number, number, number], d: 4 };

  test('planeToWorld keeps the same points on the same side, in world distances', () => {
    const w = planeToWorld(plane, voxelSize, origin);
    const len = Math.hypot(1 / 3 / 2, 2 / 3, 2 / 3 / 0.5); // |n / s|
    expect(Math.hypot(...w.normal)).toBeCloseTo(1, 12);
    for (const x of [
      [0, 0, 0],
      [7, -3, 2],
      [12, 1, 5],
    ]) {
      const inVoxels = plane.normal[0] * x[0] + plane.normal[1] * x[1] + plane.normal[2] * x[2] - plane.d;
      const p = toWorld(x);
      expect(w.normal[0] * p[0] + w.normal[1] * p[1] + w.normal[2] * p[2] - w.d).toBeCloseTo(inVoxels / len, 12);
    }
  });

  test('planeFromWorld through a point of the world plane gives the plane back (unit normal in voxels)', () => {
    const w = planeToWorld(plane, voxelSize, origin);
    const onPlane = toWorld([6, 2, 0]); // 6/3 + 4/3 + 0 = 10/3: not on it; move along n to the plane
    const k = w.d - (w.normal[0] * onPlane[0] + w.normal[1] * onPlane[1] + w.normal[2] * onPlane[2]);
    const p = onPlane.map((v, a) => v + k * w.normal[a]);
    const back = planeFromWorld(w.normal, p, voxelSize, origin);
    plane.normal.forEach((v, a) => expect(back.normal[a]).toBeCloseTo(v, 12));
    expect(back.d).toBeCloseTo(plane.d, 12);
    // turned about p: the new plane still holds p (its centre stays put)
    const turned = planeFromWorld([0, Math.SQRT1_2, Math.SQRT1_2], p, voxelSize, origin);
    const x = p.map((v, a) => v / voxelSize[a] - origin[a]);
    expect(turned.normal[0] * x[0] + turned.normal[1] * x[1] + turned.normal[2] * x[2]).toBeCloseTo(turned.d, 12);
    expect(Math.hypot(...turned.normal)).toBeCloseTo(1, 12);
  });

  test('planeCentre: the previous centre moved onto the plane while inside, else the polygon centre, else the box centre', () => {
    const x3 = { normal: [1, 0, 0] as [number, number, number], d: 3 };
    expect(planeCentre(x3, [], [0, 0, 0], [10, 10, 10], [5, 6, 7])).toEqual([3, 6, 7]);
    const square = [
      [3, 0, 0],
      [3, 10, 0],
      [3, 10, 10],
      [3, 0, 4],
    ];
    expect(planeCentre(x3, square, [0, 0, 0], [10, 10, 10], [5, 12, 7])).toEqual([3, 5, 3.5]);
    expect(planeCentre(x3, square, [0, 0, 0], [10, 10, 10])).toEqual([3, 5, 3.5]);
    expect(planeCentre({ normal: [0, 0, 2], d: 40 }, [], [0, 0, 0], [10, 10, 10])).toEqual([5, 5, 20]);
  });

  test('freePlanePolygon: the plane within the volume and the box; none when it misses them', () => {
    const dims = [128, 128, 128];
    const z = freePlanePolygon({ plane: { normal: [0, 0, 1], d: 32 } }, dims);
    expect(z).toHaveLength(4);
    for (const p of z) expect(p[2]).toBe(32);
    expect(new Set(z.map((p) => `${p[0]},${p[1]}`))).toEqual(new Set(['0,0', '127,0', '0,127', '127,127']));
    const inBox = freePlanePolygon({ box: [0, 0, 0, 64, 127, 127], plane: { normal: [0, 0, 1], d: 32 } }, dims);
    expect(Math.max(...inBox.map((p) => p[0]))).toBeCloseTo(64, 12);
    expect(freePlanePolygon({ box: [0, 0, 0, 64, 127, 20], plane: { normal: [0, 0, 1], d: 32 } }, dims)).toEqual([]);
    expect(freePlanePolygon({ plane: { normal: [0, 0, 1], d: 300 } }, dims)).toEqual([]);
    expect(freePlanePolygon({ box: [0, 0, 0, 64, 127, 127] }, dims)).toEqual([]);
  });
});
