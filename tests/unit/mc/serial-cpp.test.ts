// The serial C++ marching cubes (benchmarks/serial-mc), as the committed Wasm module
// and as a native binary, must give exactly the TS serial MC's triangle soup: same
// triangles, same order, same float32 bits.
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, test } from 'vitest';
import { WasmSerialMc } from '../../../src/mc/serial-mc-wasm.ts';
import { meshMetrics } from '../../../src/mc/mesh-metrics.ts';
import { marchingCubes } from '../../../src/mc/serial-mc.ts';
import { ROOT, SHARED_DATA, asFloat32, loadMcReference, rng } from './reference.ts';

type Dims = [number, number, number];

function randomVolume(seed: number, dims: Dims): Float32Array {
  const r = rng(seed);
  const [nx, ny, nz] = dims;
  const v = new Float32Array(nx * ny * nz);
  // Smooth blobs plus noise, so there are surfaces of every size and all cases.
  const c = [r() * nx, r() * ny, r() * nz];
  for (let z = 0, p = 0; z < nz; z++)
    for (let y = 0; y < ny; y++) for (let x = 0; x < nx; x++) v[p++] = Math.hypot(x - c[0], y - c[1], z - c[2]) * 0.3 + r() * 2;
  return v;
}

const SMALL: { seed: number; dims: Dims; isos: number[] }[] = [
  { seed: 1, dims: [9, 7, 8], isos: [1.3137, 2.0213] },
  { seed: 2, dims: [17, 3, 21], isos: [1.7731, 2.9011] },
  { seed: 3, dims: [2, 2, 2], isos: [0.9137] },
  { seed: 4, dims: [33, 30, 31], isos: [2.5171, 4.1009, 1e9] },
];

function sameBits(a: Float32Array, b: Float32Array): boolean {
  return (
    a.length === b.length &&
    Buffer.compare(Buffer.from(a.buffer, a.byteOffset, a.byteLength), Buffer.from(b.buffer, b.byteOffset, b.byteLength)) === 0
  );
}

const fuel = loadMcReference().volumes.find((v) => v.file === 'volumes/fuel_64x64x64_float32.raw')!;
const fuelValues = () => asFloat32(readFileSync(join(SHARED_DATA, fuel.file)));

describe('Wasm module (committed dist/)', () => {
  let wasm: WasmSerialMc;
  beforeAll(async () => {
    wasm = await WasmSerialMc.create();
  });
  afterAll(() => wasm.dispose());

  test('random small volumes: bit-identical soups', () => {
    for (const { seed, dims, isos } of SMALL) {
      const values = randomVolume(seed, dims);
      wasm.setVolume(values, dims);
      for (const iso of isos) {
        const ts = marchingCubes(values, dims, iso);
        const w = wasm.run(iso);
        expect([seed, iso, w.triangleCount]).toEqual([seed, iso, ts.triangleCount]);
        expect(sameBits(w.positions!, ts.positions), `seed ${seed} iso ${iso}`).toBe(true);
      }
    }
  });

  test(`${fuel.file}: bit-identical soups at the mc.json isovalues`, () => {
    const values = fuelValues();
    wasm.setVolume(values, fuel.dims_xyz);
    for (const s of fuel.isosurfaces) {
      const ts = marchingCubes(values, fuel.dims_xyz, s.iso);
      const w = wasm.run(s.iso);
      expect(w.triangleCount).toBe(s.vtkMarchingCubes.triangles);
      expect(sameBits(w.positions!, ts.positions)).toBe(true);
      expect(wasm.run(s.iso, { copyOut: false })).toEqual({ triangleCount: ts.triangleCount, positions: null });
    }
  });

  test('run before setVolume and bad dims throw', async () => {
    const fresh = await WasmSerialMc.create();
    expect(() => fresh.run(1)).toThrow(/setVolume/);
    expect(() => fresh.setVolume(new Float32Array(7), [2, 2, 2])).toThrow();
  });
});

const hasGxx = (() => {
  try {
    execFileSync(process.env.CXX || 'g++', ['--version'], { stdio: 'ignore' });
    return true;
  } catch {
    return false;
  }
})();

describe.skipIf(!hasGxx)('native binary (g++ -O3)', () => {
  let dir = '';
  let binary = '';
  beforeAll(() => {
    dir = mkdtempSync(join(tmpdir(), 'zfpiso-mc-native-'));
    binary = execFileSync(process.execPath, [join(ROOT, 'benchmarks', 'serial-mc', 'build.mjs'), 'native', '--if-stale'], {
      encoding: 'utf8',
    })
      .trim()
      .split('\n')
      .pop()!;
  }, 120_000);
  afterAll(() => rmSync(dir, { recursive: true, force: true }));

  function runNative(file: string, dims: Dims, isos: number[], dtype = 'float32') {
    const args = [file, ...dims.map(String), isos.map((x) => String(Math.fround(x))).join(','), '--dtype', dtype, '--dump', dir];
    return JSON.parse(execFileSync(binary, args, { encoding: 'utf8' })) as { results: { triangles: number; area: number; ms: number[] }[] };
  }

  test('random small volumes and fuel: bit-identical soups, same counts and areas', () => {
    const inputs: { file: string; values: Float32Array; dims: Dims; isos: number[] }[] = SMALL.map(({ seed, dims, isos }) => {
      const values = randomVolume(seed, dims);
      const file = join(dir, `v${seed}.f32`);
      writeFileSync(file, values);
      return { file, values, dims, isos };
    });
    inputs.push({
      file: join(SHARED_DATA, fuel.file),
      values: fuelValues(),
      dims: fuel.dims_xyz,
      isos: fuel.isosurfaces.map((s) => s.iso),
    });
    for (const { file, values, dims, isos } of inputs) {
      const report = runNative(file, dims, isos);
      isos.forEach((iso, q) => {
        const ts = marchingCubes(values, dims, iso);
        expect(report.results[q].triangles).toBe(ts.triangleCount);
        expect(report.results[q].area).toBeCloseTo(meshMetrics(ts.positions).area, 6);
        expect(sameBits(asFloat32(readFileSync(join(dir, `soup_${q}.f32`))), ts.positions), `${file} iso ${iso}`).toBe(true);
      });
    }
  });

  test('uint8 input is converted exactly', () => {
    const v = loadMcReference().volumes.find((x) => x.dtype === 'uint8')!;
    const report = runNative(join(SHARED_DATA, v.file), v.dims_xyz, [v.isosurfaces[1].iso], 'uint8');
    expect(report.results[0].triangles).toBe(v.isosurfaces[1].vtkMarchingCubes.triangles);
  });
});
