// Serial TS marching cubes: conventions on hand-made cubes, VTK's exact soups on
// random volumes, and closed surfaces.
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, test } from 'vitest';
import { caseIndex } from '../../../src/mc/case-table.ts';
import { compareTriangleSoups, meshMetrics } from '../../../src/mc/mesh-metrics.ts';
import { marchingCubes } from '../../../src/mc/serial-mc.ts';
import { asFloat32, rng, runReferenceTool } from './reference.ts';

function cube(corners: number[]): Float32Array {
  return Float32Array.from(corners); // 2x2x2: grid point c = x + 2y + 4z is corner c
}

describe('one cell', () => {
  test('corner 0 inside: vertices at t = (iso - v0) / (v1 - v0) from each lower corner, normal away from it', () => {
    const { positions, triangleCount } = marchingCubes(cube([1, 0, 0, 0, 0, 0, 0, 0]), [2, 2, 2], 0.25);
    expect(triangleCount).toBe(1);
    // Edges 0 (x), 4 (y), 8 (z): t = (0.25 - 1) / (0 - 1) = 0.75.
    expect(Array.from(positions)).toEqual([0.75, 0, 0, 0, 0.75, 0, 0, 0, 0.75]);
  });

  test('corner 7 inside: t measured from the lower (outside) corner', () => {
    const { positions } = marchingCubes(cube([0, 0, 0, 0, 0, 0, 0, 1]), [2, 2, 2], 0.25);
    // Edges 3 (x, from corner 6), 7 (y, from 5), 11 (z, from 3): t = 0.25.
    const verts = [];
    for (let v = 0; v < 9; v += 3) verts.push(Array.from(positions.subarray(v, v + 3)));
    expect(verts.sort()).toEqual(
      [
        [0.25, 1, 1],
        [1, 0.25, 1],
        [1, 1, 0.25],
      ].sort(),
    );
    // Normal (p1-p0)x(p2-p0) toward decreasing values: toward corner 0, away from corner 7.
    const [p0, p1, p2] = [0, 3, 6].map((o) => Array.from(positions.subarray(o, o + 3)));
    const a = p1.map((x, i) => x - p0[i]);
    const b = p2.map((x, i) => x - p0[i]);
    const n = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    expect(n[0] + n[1] + n[2]).toBeLessThan(0);
  });

  test('value == iso counts as inside', () => {
    expect(marchingCubes(cube([2, 0, 0, 0, 0, 0, 0, 0]), [2, 2, 2], 2).triangleCount).toBe(1);
    expect(marchingCubes(cube([2, 2, 2, 2, 2, 2, 2, 2]), [2, 2, 2], 2).triangleCount).toBe(0);
  });

  test('interpolation is float32: each operation rounded, then base + t', () => {
    const f = Math.fround;
    // Float32 inputs for which float32 and float64 arithmetic give different t.
    const v0 = f(-45.29553985595703);
    const v1 = f(127.886474609375);
    const iso = 27.92963981628418;
    // Corner 1 inside (v1 >= iso), the rest outside: case 2, first vertex on edge 0.
    const { positions } = marchingCubes(cube([v0, v1, v0, v0, v0, v0, v0, v0]), [2, 2, 2], iso);
    const t = f(f(iso - v0) / f(v1 - v0));
    expect(t).not.toBe(f((iso - v0) / (v1 - v0)));
    expect(positions[0]).toBe(t); // edge 0 from corner 0 along x is the first vertex of case 2
    expect(positions[1]).toBe(0);
    expect(positions[2]).toBe(0);
  });

  test('the cell at the far corner of a larger grid is offset by its index', () => {
    const dims: [number, number, number] = [5, 4, 3];
    const values = new Float32Array(60);
    values[4 + 5 * (3 + 4 * 2)] = 1; // grid point (4, 3, 2): corner 7 of cell (3, 2, 1)
    const { positions } = marchingCubes(values, dims, 0.5);
    const verts = [];
    for (let v = 0; v < positions.length; v += 3) verts.push(Array.from(positions.subarray(v, v + 3)));
    expect(verts.sort()).toEqual(
      [
        [3.5, 3, 2],
        [4, 2.5, 2],
        [4, 3, 1.5],
      ].sort(),
    );
  });
});

describe('degenerate input', () => {
  test('a dimension of 1 gives no cells', () => {
    expect(marchingCubes(new Float32Array(8), [8, 1, 1], 0.5).triangleCount).toBe(0);
  });
  test('dims must match the data', () => {
    expect(() => marchingCubes(new Float32Array(7), [2, 2, 2], 0.5)).toThrow(/dims/);
    expect(() => marchingCubes(new Float32Array(8), [2, 2, 2.5], 0.5)).toThrow(/dims/);
  });
});

describe('against vtkMarchingCubes soups', () => {
  let dir = '';
  beforeAll(() => {
    dir = mkdtempSync(join(tmpdir(), 'zfpiso-mc-vtk-'));
  });
  afterAll(() => rmSync(dir, { recursive: true, force: true }));

  const cases: {
    name: string;
    dims: [number, number, number];
    field: (x: number, y: number, z: number, r: () => number) => number;
    iso: number;
  }[] = [
    { name: 'noise 7x5x9', dims: [7, 5, 9], field: (_x, _y, _z, r) => r(), iso: 0.4137 },
    { name: 'noise 12x11x10', dims: [12, 11, 10], field: (_x, _y, _z, r) => r() * 10 - 5, iso: 0.0313 },
    {
      name: 'sphere plus noise 20x18x16',
      dims: [20, 18, 16],
      field: (x, y, z, r) => Math.hypot(x - 9.3, y - 8.1, z - 7.7) + r() * 0.8,
      iso: 5.2371,
    },
    {
      // Cell (3a, 0, 3b) holds case c = a + 16b: every case, with random corner values.
      name: 'all 256 cases 48x2x48',
      dims: [48, 2, 48],
      field: (x, y, z, r) => {
        const c = Math.floor(x / 3) + 16 * Math.floor(z / 3);
        const dx = x % 3;
        const dz = z % 3;
        if (dx === 2 || dz === 2) return r();
        return (c >> (dx + 2 * y + 4 * dz)) & 1 ? 0.6 + 0.4 * r() : 0.4 * r();
      },
      iso: 0.5013,
    },
    {
      name: 'gyroid 24x24x24',
      dims: [24, 24, 24],
      field: (x, y, z) =>
        Math.sin(x / 2.1) * Math.cos(y / 2.3) + Math.sin(y / 2.3) * Math.cos(z / 1.9) + Math.sin(z / 1.9) * Math.cos(x / 2.1),
      iso: 0.1237,
    },
  ];
  cases.forEach((c, n) => {
    test(`${c.name}: the same triangles, vertex order up to rotation, within 1e-5`, () => {
      const r = rng(1000 + n);
      const [nx, ny, nz] = c.dims;
      const values = new Float32Array(nx * ny * nz);
      for (let z = 0, p = 0; z < nz; z++) for (let y = 0; y < ny; y++) for (let x = 0; x < nx; x++) values[p++] = c.field(x, y, z, r);
      expect(values.includes(Math.fround(c.iso))).toBe(false);
      if (c.name.startsWith('all 256')) {
        const seen = new Set<number>();
        const at = (x: number, y: number, z: number) => values[x + nx * (y + ny * z)];
        for (let z = 0; z < nz - 1; z++)
          for (let x = 0; x < nx - 1; x++)
            seen.add(
              caseIndex(
                [0, 1, 2, 3, 4, 5, 6, 7].map((q) => at(x + (q & 1), (q >> 1) & 1, z + (q >> 2))),
                c.iso,
              ),
            );
        expect(seen.size).toBe(256);
      }
      const input = join(dir, `v${n}.f32`);
      const output = join(dir, `v${n}.soup.f32`);
      writeFileSync(input, values);
      const answer = runReferenceTool(['vtk-soup', input, `${nx}`, `${ny}`, `${nz}`, `${Math.fround(c.iso)}`, output]);
      const vtk = asFloat32(readFileSync(output));
      const ours = marchingCubes(values, c.dims, c.iso);
      expect(answer.triangles).toBeGreaterThan(50);
      expect(ours.triangleCount).toBe(answer.triangles);
      const cmp = compareTriangleSoups(ours.positions, vtk, { tolerance: 1e-5 });
      expect(cmp, JSON.stringify({ ...cmp, examplesA: cmp.examplesA.slice(0, 2), examplesB: cmp.examplesB.slice(0, 2) })).toMatchObject({
        equal: true,
        matched: answer.triangles,
      });
    });
  });
});

test('a surface inside the volume is closed and consistently oriented', () => {
  // Every directed edge (a -> b) of a closed, consistently wound soup appears once,
  // and its reverse (b -> a) once: vertices on shared grid edges must be bit-identical.
  const n = 40;
  const r = rng(7);
  const values = new Float32Array(n * n * n);
  for (let z = 0, p = 0; z < n; z++)
    for (let y = 0; y < n; y++)
      for (let x = 0; x < n; x++)
        values[p++] = 12 - Math.hypot(x - 19.6, y - 20.2, z - 19.1) + 2 * Math.sin(x * 0.7) * Math.cos(y * 0.5) + r();
  const { positions, triangleCount } = marchingCubes(values, [n, n, n], 0.5);
  expect(triangleCount).toBeGreaterThan(1000);
  const key = (v: number) => `${positions[3 * v]},${positions[3 * v + 1]},${positions[3 * v + 2]}`;
  const directed = new Map<string, number>();
  for (let t = 0; t < triangleCount; t++) {
    for (let k = 0; k < 3; k++) {
      const e = `${key(3 * t + k)}>${key(3 * t + ((k + 1) % 3))}`;
      directed.set(e, (directed.get(e) ?? 0) + 1);
    }
  }
  let bad = 0;
  for (const [e, count] of directed) {
    const [a, b] = e.split('>');
    if (count !== 1 || directed.get(`${b}>${a}`) !== 1) bad++;
  }
  expect(bad).toBe(0);
  // Closed surface around the high-value region: outward normals (toward decreasing
  // values) give a positive signed volume.
  let vol = 0;
  for (let p = 0; p < positions.length; p += 9) {
    const [ax, ay, az, bx, by, bz, cx, cy, cz] = positions.subarray(p, p + 9);
    vol += (ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)) / 6;
  }
  expect(vol).toBeGreaterThan(0);
  expect(meshMetrics(positions).degenerate).toBe(0);
});
