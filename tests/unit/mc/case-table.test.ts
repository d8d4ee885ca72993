// The committed case table against a fresh derivation from VTK, plus structural checks.
import { execFileSync } from 'node:child_process';
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { describe, expect, test } from 'vitest';
import {
  CASE_EDGE_MASK,
  CASE_EDGE_TABLE,
  CASE_TABLE_STRIDE,
  CASE_TRIANGLE_EDGES,
  CASE_VERTEX_COUNT,
  CORNER_OFFSETS,
  EDGE_AXIS,
  EDGE_CORNERS,
  caseIndex,
  packCaseTable,
} from '../../../src/mc/case-table.ts';
import { ROOT, venvPython } from './reference.ts';

const corner = (c: number) => [CORNER_OFFSETS[3 * c], CORNER_OFFSETS[3 * c + 1], CORNER_OFFSETS[3 * c + 2]];
const midpoint = (e: number) => {
  const a = corner(EDGE_CORNERS[2 * e]);
  const b = corner(EDGE_CORNERS[2 * e + 1]);
  return [0, 1, 2].map((i) => (a[i] + b[i]) / 2);
};

test('committed table equals a fresh derivation from VTK vtkMarchingCubes', () => {
  const out = execFileSync(venvPython(), [join(ROOT, 'tools', 'mc', 'derive-case-table.py'), '--json'], { encoding: 'utf8' });
  const derived = JSON.parse(out) as { edges: number[][]; cases: number[][] };
  expect(derived.edges).toEqual(Array.from({ length: 12 }, (_, e) => [EDGE_CORNERS[2 * e], EDGE_CORNERS[2 * e + 1], EDGE_AXIS[e]]));
  expect(derived.cases.length).toBe(256);
  for (let c = 0; c < 256; c++) expect([c, ...CASE_TRIANGLE_EDGES[c]]).toEqual([c, ...derived.cases[c]]);
}, 60_000);

test('the C header for the C++ MC holds the same table', () => {
  const h = readFileSync(join(ROOT, 'benchmarks', 'serial-mc', 'mc_tables.h'), 'utf8');
  const block = (name: string) => {
    const m = new RegExp(`${name}[^=]*=\\s*\\{([\\s\\S]*?)\\n\\};`).exec(h);
    if (!m) throw new Error(`${name} not found in mc_tables.h`);
    return m[1]
      .replace(/\/\*[\s\S]*?\*\//g, '')
      .match(/-?\d+/g)!
      .map(Number);
  };
  expect(block('MC_EDGE_CORNERS')).toEqual(
    Array.from({ length: 12 }, (_, e) => [EDGE_CORNERS[2 * e], EDGE_CORNERS[2 * e + 1], EDGE_AXIS[e]]).flat(),
  );
  expect(block('MC_CASE_VERTEX_COUNT')).toEqual(Array.from(CASE_VERTEX_COUNT));
  expect(block('MC_CASE_TRIANGLE_EDGES')).toEqual(Array.from(CASE_EDGE_TABLE));
});

describe('numbering', () => {
  test('corner c is at offset (c & 1, c >> 1 & 1, c >> 2)', () => {
    expect(Array.from(CORNER_OFFSETS)).toEqual([0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1, 1, 1, 1]);
  });
  test('edges: 4 per axis, lower to upper corner, all 12 cube edges once', () => {
    expect(Array.from(EDGE_CORNERS)).toEqual([0, 1, 2, 3, 4, 5, 6, 7, 0, 2, 1, 3, 4, 6, 5, 7, 0, 4, 1, 5, 2, 6, 3, 7]);
    const seen = new Set<string>();
    for (let e = 0; e < 12; e++) {
      const lo = EDGE_CORNERS[2 * e];
      const hi = EDGE_CORNERS[2 * e + 1];
      expect(EDGE_AXIS[e]).toBe(e >> 2);
      expect(lo & (1 << EDGE_AXIS[e])).toBe(0);
      expect(hi).toBe(lo | (1 << EDGE_AXIS[e]));
      seen.add(`${lo}-${hi}`);
    }
    expect(seen.size).toBe(12);
  });
});

describe('structure', () => {
  test('vertex counts, padding, empty cases', () => {
    expect(CASE_TRIANGLE_EDGES.length).toBe(256);
    for (let c = 0; c < 256; c++) {
      const n = CASE_VERTEX_COUNT[c];
      expect(n % 3).toBe(0);
      expect(n).toBeLessThanOrEqual(15);
      expect(n === 0).toBe(c === 0 || c === 255);
      for (let j = 0; j < CASE_TABLE_STRIDE; j++)
        expect(CASE_EDGE_TABLE[c * CASE_TABLE_STRIDE + j]).toBe(j < n ? CASE_TRIANGLE_EDGES[c][j] : -1);
    }
  });

  test('triangles use exactly the crossed edges, each triangle three distinct edges', () => {
    for (let c = 1; c < 255; c++) {
      const tri = CASE_TRIANGLE_EDGES[c];
      const used = tri.reduce((m, e) => m | (1 << e), 0);
      expect([c, used]).toEqual([c, CASE_EDGE_MASK[c]]);
      for (let t = 0; t < tri.length; t += 3) expect(new Set(tri.slice(t, t + 3)).size).toBe(3);
    }
    // A crossed edge has one inside and one outside corner.
    expect(CASE_EDGE_MASK[1]).toBe((1 << 0) | (1 << 4) | (1 << 8));
    expect(CASE_EDGE_MASK[0b1111]).toBe(0b1111 << 8);
  });

  test('winding: normals point from inside corners toward outside ones', () => {
    // For each triangle, the normal of its edge midpoints against the directions
    // of its three edges from the inside corner to the outside one.
    for (let c = 1; c < 255; c++) {
      const tri = CASE_TRIANGLE_EDGES[c];
      for (let t = 0; t < tri.length; t += 3) {
        const [p0, p1, p2] = tri.slice(t, t + 3).map(midpoint);
        const a = [p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]];
        const b = [p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]];
        const n = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
        let dot = 0;
        for (const e of tri.slice(t, t + 3)) {
          const lo = EDGE_CORNERS[2 * e];
          const sign = (c >> lo) & 1 ? 1 : -1; // +1: lower corner inside, so outward is +axis
          dot += sign * n[EDGE_AXIS[e]];
        }
        expect([c, t, dot > 0]).toEqual([c, t, true]);
      }
    }
  });

  test('complementary case crosses the same edges', () => {
    for (let c = 0; c < 256; c++) expect(CASE_EDGE_MASK[255 - c]).toBe(CASE_EDGE_MASK[c]);
  });
});

test('packCaseTable round-trips through the nibble layout a kernel reads', () => {
  const packed = packCaseTable();
  expect(packed.length).toBe(512);
  for (let c = 0; c < 256; c++) {
    const nib = (j: number) => (packed[2 * c + (j >> 3)] >>> (4 * (j & 7))) & 15;
    expect(nib(15)).toBe(CASE_VERTEX_COUNT[c] / 3);
    for (let j = 0; j < 15; j++) expect(nib(j)).toBe(j < CASE_VERTEX_COUNT[c] ? CASE_TRIANGLE_EDGES[c][j] : 15);
  }
});

test('caseIndex: bit c set when corner c >= iso (iso rounded to float32)', () => {
  expect(caseIndex([1, 0, 0, 0, 0, 0, 0, 0], 0.5)).toBe(1);
  expect(caseIndex([0, 0, 0, 0, 0, 0, 0, 2], 2)).toBe(128);
  expect(caseIndex([0.1, 0, 0, 0, 0, 0, 0, 0], 0.1)).toBe(0); // double 0.1 < fround(0.1): the iso is float32
  expect(caseIndex(new Float32Array([0.1, 0, 0, 0, 0, 0, 0, 0]), 0.1)).toBe(1);
  expect(caseIndex([5, 5, 5, 5, 5, 5, 5, 5], 4)).toBe(255);
});
