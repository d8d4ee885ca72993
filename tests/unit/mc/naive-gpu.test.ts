// Naive data-parallel GPU marching cubes (src/mc/naive-gpu.ts) against the
// serial TS marching cubes: the same triangles, compared as sets (winding
// included) within float32 division rounding, the same counts, and the same
// vertex order per cell (the soups are compared as sets, since cells finish in
// any order on the GPU). Random volumes of awkward sizes (no cells, one cell,
// sizes not multiples of anything, long thin ones), 2D/3D dispatch grids, soup
// growth from a tiny buffer, an isovalue above and below every value, several
// isovalues through one instance, and the shared fuel and hydrogen volumes at
// mc.json's isovalues (whose triangle counts must also equal VTK's).
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, describe, expect, test } from 'vitest';
import { compareTriangleSoups } from '../../../src/mc/mesh-metrics.ts';
import { NaiveMarchingCubes, type NaiveMcOptions } from '../../../src/mc/naive-gpu.ts';
import { marchingCubes, type Dims3 } from '../../../src/mc/serial-mc.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { loadMcReference, loadMcVolume, rng } from './reference.ts';

// WGSL's f32 division may be off by 2.5 ULP; coordinates are below 2^8 here.
const TOLERANCE = 2e-5;

type Kind = 'noise' | 'blobs';

function makeField(dims: Dims3, seed: number, kind: Kind): Float32Array {
  const [nx, ny, nz] = dims;
  const r = rng(seed);
  const out = new Float32Array(nx * ny * nz);
  if (kind === 'noise') {
    for (let i = 0; i < out.length; i++) out[i] = r() * 100 - 20;
    return out;
  }
  const centres = Array.from({ length: 4 }, () => [r() * nx, r() * ny, r() * nz, 2 + r() * Math.max(nx, ny, nz) * 0.4]);
  let i = 0;
  for (let z = 0; z < nz; z++)
    for (let y = 0; y < ny; y++)
      for (let x = 0; x < nx; x++) {
        let v = 0;
        for (const [cx, cy, cz, s] of centres) v += 100 * Math.exp(-((x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2) / (s * s));
        out[i++] = v + r() * 3;
      }
  return out;
}

function upload(device: GPUDevice, values: Float32Array): GPUBuffer {
  const buffer = device.createBuffer({
    label: 'test.volume',
    size: Math.max(4, values.byteLength),
    usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST,
  });
  if (values.byteLength > 0) device.queue.writeBuffer(buffer, 0, values as Float32Array<ArrayBuffer>);
  return buffer;
}

async function expectSameSurface(mc: NaiveMarchingCubes, volume: GPUBuffer, values: Float32Array, dims: Dims3, iso: number, label: string) {
  const r = await mc.extract(volume, iso);
  const cpu = marchingCubes(values, dims, iso);
  expect(r.triangles, `${label} iso ${iso}: triangles`).toBe(cpu.triangleCount);
  expect(r.vertices).toBe(cpu.triangleCount * 3);
  const gpu = await mc.readPositions(r.vertices);
  const cmp = compareTriangleSoups(gpu, cpu.positions, { tolerance: TOLERANCE });
  expect(
    cmp.equal,
    `${label} iso ${iso}: ${JSON.stringify({ ...cmp, examplesA: cmp.examplesA.slice(0, 2), examplesB: cmp.examplesB.slice(0, 2) })}`,
  ).toBe(true);
  return r;
}

interface Case {
  dims: Dims3;
  kind: Kind;
  options?: Partial<NaiveMcOptions>;
}

const CASES: Case[] = [
  { dims: [1, 6, 5], kind: 'noise' }, // no cells at all
  { dims: [2, 2, 2], kind: 'noise' }, // one cell
  { dims: [3, 7, 5], kind: 'noise' },
  { dims: [17, 9, 13], kind: 'noise', options: { maxWorkgroupsPerDimension: 3 } }, // 2D and 3D grids
  { dims: [33, 18, 7], kind: 'blobs', options: { initialVertexCapacity: 3 } }, // the soup grows
  { dims: [65, 3, 40], kind: 'noise', options: { maxWorkgroupsPerDimension: 7, initialVertexCapacity: 100 } },
  { dims: [29, 31, 23], kind: 'blobs' },
];

describe('naive GPU marching cubes = serial marching cubes', () => {
  for (const c of CASES) {
    gpuTest(`${c.dims.join('x')} ${c.kind}${c.options ? ' ' + JSON.stringify(c.options) : ''}`, async ({ gpu }) => {
      const { device } = gpu;
      const values = makeField(c.dims, c.dims[0] * 7 + c.dims[1] * 131 + c.dims[2], c.kind);
      const volume = upload(device, values);
      const mc = await NaiveMarchingCubes.create(device, { dims: c.dims, ...c.options });
      try {
        let lo = Infinity;
        let hi = -Infinity;
        for (const v of values) {
          lo = Math.min(lo, v);
          hi = Math.max(hi, v);
        }
        const random = rng(c.dims[2] * 17 + 3);
        let grew = false;
        let anyTriangles = false;
        for (let k = 0; k < 4; k++) {
          const iso = Math.fround(lo + (hi - lo) * (0.1 + 0.8 * random()));
          const r = await expectSameSurface(mc, volume, values, c.dims, iso, c.dims.join('x'));
          grew ||= r.grew;
          anyTriangles ||= r.triangles > 0;
          expect(r.gpuMs).toBeGreaterThanOrEqual(0);
          expect(r.activeCells).toBeLessThanOrEqual(mc.cellCount);
        }
        if (mc.cellCount > 0) expect(anyTriangles).toBe(true);
        if (c.options?.initialVertexCapacity) expect(grew).toBe(true);
        // Above and below every value: no active cell, nothing emitted.
        for (const iso of [hi + 1, lo - 1]) {
          const r = await mc.extract(volume, iso);
          expect(r.activeCells).toBe(0);
          expect(r.triangles).toBe(0);
        }
      } finally {
        mc.destroy();
        volume.destroy();
      }
    });
  }

  gpuTest('the active-cell count is the number of cells with a sign change', async ({ gpu }) => {
    const dims: Dims3 = [11, 6, 9];
    const values = makeField(dims, 5, 'noise');
    const volume = upload(gpu.device, values);
    const mc = await NaiveMarchingCubes.create(gpu.device, { dims });
    try {
      const iso = Math.fround(31.7);
      const r = await mc.extract(volume, iso);
      let active = 0;
      const [nx, ny, nz] = dims;
      for (let k = 0; k < nz - 1; k++)
        for (let j = 0; j < ny - 1; j++)
          for (let i = 0; i < nx - 1; i++) {
            let inside = 0;
            for (let c = 0; c < 8; c++) inside += values[i + (c & 1) + nx * (j + ((c >> 1) & 1) + ny * (k + (c >> 2)))] >= iso ? 1 : 0;
            if (inside > 0 && inside < 8) active++;
          }
      expect(r.activeCells).toBe(active);
    } finally {
      mc.destroy();
      volume.destroy();
    }
  });

  gpuTest('refuses a volume buffer smaller than its dims', async ({ gpu }) => {
    const mc = await NaiveMarchingCubes.create(gpu.device, { dims: [4, 4, 4] });
    const small = upload(gpu.device, new Float32Array(10));
    try {
      await expect(mc.extract(small, 1)).rejects.toThrow(/needs 256/);
    } finally {
      mc.destroy();
      small.destroy();
    }
  });
});

describe('shared volumes', () => {
  const dir = mkdtempSync(join(tmpdir(), 'naive-mc-'));
  afterAll(() => rmSync(dir, { recursive: true, force: true }));
  const volumes = loadMcReference().volumes.filter((v) => /^volumes\/(fuel|hydrogen_atom)_.*float32\.raw$/.test(v.file));

  test('fuel and hydrogen are in mc.json', () => {
    expect(volumes.map((v) => v.file).sort()).toEqual([
      'volumes/fuel_64x64x64_float32.raw',
      'volumes/hydrogen_atom_128x128x128_float32.raw',
    ]);
  });

  for (const v of volumes) {
    gpuTest(`${v.file}: every mc.json isovalue = serial MC, triangle counts = vtkMarchingCubes`, async ({ gpu }) => {
      const values = loadMcVolume(v, dir);
      const volume = upload(gpu.device, values);
      const mc = await NaiveMarchingCubes.create(gpu.device, { dims: v.dims_xyz });
      try {
        for (const s of v.isosurfaces) {
          const r = await expectSameSurface(mc, volume, values, v.dims_xyz, s.iso, v.file);
          expect(r.triangles).toBe(s.vtkMarchingCubes.triangles);
          expect(r.activeCells).toBe(s.active_cells);
        }
      } finally {
        mc.destroy();
        volume.destroy();
      }
    });
  }
});
