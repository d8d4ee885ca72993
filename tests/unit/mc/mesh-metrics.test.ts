import { describe, expect, test } from 'vitest';
import { compareTriangleSoups, meshMetrics } from '../../../src/mc/mesh-metrics.ts';
import { rng } from './reference.ts';

const soup = (...tris: number[][]) => Float32Array.from(tris.flat());

describe('meshMetrics', () => {
  test('area, bbox, degenerate count', () => {
    const m = meshMetrics(soup([0, 0, 0, 2, 0, 0, 0, 3, 0], [1, 1, 1, 1, 1, 1, 4, 5, 6], [0, 0, -1, 0, 0, 1, 0, 2, 0]));
    expect(m.triangles).toBe(3);
    expect(m.area).toBeCloseTo(3 + 0 + 2, 12);
    expect(m.degenerate).toBe(1);
    expect(m.bbox).toEqual({ min: [0, 0, -1], max: [4, 5, 6] });
  });
  test('empty soup, prefix of a larger buffer, bad length', () => {
    expect(meshMetrics(new Float32Array(0))).toEqual({ triangles: 0, area: 0, bbox: null, degenerate: 0 });
    const m = meshMetrics(soup([0, 0, 0, 1, 0, 0, 0, 1, 0], [9, 9, 9, 9, 9, 9, 9, 9, 9]), 3);
    expect(m.triangles).toBe(1);
    expect(m.bbox!.max).toEqual([1, 1, 0]);
    expect(() => meshMetrics(new Float32Array(12))).toThrow();
  });
});

describe('compareTriangleSoups', () => {
  const r = rng(3);
  const random = (n: number) => Float32Array.from({ length: 9 * n }, () => Math.floor(r() * 64) + r());

  function shuffleAndRotate(s: Float32Array): Float32Array {
    const n = s.length / 9;
    const order = Array.from({ length: n }, (_, i) => i);
    for (let i = n - 1; i > 0; i--) {
      const j = Math.floor(r() * (i + 1));
      [order[i], order[j]] = [order[j], order[i]];
    }
    const out = new Float32Array(s.length);
    order.forEach((t, dst) => {
      const rot = Math.floor(r() * 3);
      for (let v = 0; v < 3; v++) out.set(s.subarray(9 * t + 3 * ((v + rot) % 3), 9 * t + 3 * ((v + rot) % 3) + 3), 9 * dst + 3 * v);
    });
    return out;
  }

  test('same triangles in another order and rotation are equal', () => {
    const a = random(500);
    const c = compareTriangleSoups(a, shuffleAndRotate(a), { tolerance: 0 });
    expect(c).toMatchObject({ equal: true, matched: 500, unmatchedA: 0, unmatchedB: 0, maxDifference: 0 });
  });

  test('a reflected triangle (flipped winding) does not match', () => {
    const a = random(50);
    const b = a.slice();
    b.set([b[3], b[4], b[5], b[0], b[1], b[2]], 0); // swap vertices 0 and 1 of triangle 0
    const c = compareTriangleSoups(a, b);
    expect(c).toMatchObject({ equal: false, matched: 49, unmatchedA: 1, unmatchedB: 1 });
    expect(c.examplesB.length).toBe(1);
  });

  test('small perturbations within tolerance match, even when they change the sort order', () => {
    // Vertices that tie in x and y and differ by less than tol in z make the
    // canonical rotation and sort order differ between the two sides.
    const a = soup([5, 5, 1, 6, 5, 1, 5, 6, 1], [5, 5, 1.00001, 5, 6, 1, 6, 5, 1], [1, 2, 3, 4, 5, 6, 7, 8, 9]);
    const b = soup([5, 5, 1.00002, 6, 5, 1, 5, 6, 1], [5, 5, 1, 5, 6, 1, 6, 5, 1], [1, 2, 3, 4, 5, 6, 7, 8.00003, 9]);
    expect(compareTriangleSoups(a, b, { tolerance: 1e-4 })).toMatchObject({ equal: true, matched: 3 });
    const strict = compareTriangleSoups(a, b, { tolerance: 1e-6 });
    expect(strict.equal).toBe(false);
    expect(strict.unmatchedA).toBe(3);
    const big = random(2000);
    const moved = shuffleAndRotate(big).map((x) => x + (r() - 0.5) * 1e-5);
    const c = compareTriangleSoups(big, moved, { tolerance: 1e-5 });
    expect(c.equal).toBe(true);
    expect(c.maxDifference).toBeGreaterThan(0);
    expect(c.maxDifference).toBeLessThanOrEqual(1e-5);
  });

  test('different counts, duplicates and NaN are not equal', () => {
    const a = random(10);
    expect(compareTriangleSoups(a, a.subarray(0, 81))).toMatchObject({ equal: false, unmatchedA: 1, unmatchedB: 0 });
    const dup = new Float32Array(90);
    dup.set(a.subarray(0, 81));
    dup.set(a.subarray(0, 9), 81); // triangle 0 twice, triangle 9 missing
    expect(compareTriangleSoups(a, dup)).toMatchObject({ equal: false, unmatchedA: 1, unmatchedB: 1 });
    const nan = a.slice();
    nan[4] = NaN;
    expect(compareTriangleSoups(a, nan).equal).toBe(false);
    expect(compareTriangleSoups(nan, nan).equal).toBe(false);
  });
});
