// Volumes wider than 16384 voxels on an axis (issue 36: "no size limit per
// axis"): a vertex's 36-bit block field gives each axis the bits it needs
// past 4096 blocks (shaders/isosurface/vertex_format.wgsl), so a 20000 x 8 x 6
// or a 5 x 6 x 26730 volume is a surface like any other. Checked against
// vtkMarchingCubes on the same values (integers 0..255 as float32, which
// rate 20 reproduces bit for bit: checked by the decode's SHA-256), and the
// surface reaches the far end of the long axis.
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, describe, expect } from 'vitest';
import { Isosurface } from '../../../src/isosurface/isosurface.ts';
import { meshMetrics } from '../../../src/mc/mesh-metrics.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { repoRoot, runPython } from '../../helpers/python.ts';
import { sha256 } from '../mc/reference.ts';
import { compressVolume, decodeVolume, drawnSoup, testKernelOptions } from './helpers.ts';

const VTK = readFileSync(join(repoRoot, 'tests/fixtures/vtk-surface.py'), 'utf8');
const work = mkdtempSync(join(tmpdir(), 'zfpiso-wide-'));
afterAll(() => rmSync(work, { recursive: true, force: true }));

/** Integer values 0..255 (exact at rate 20): a wave along the long axis, so the surface crosses it from end to end. */
function wideField(dims: [number, number, number], long: number): Float32Array {
  const out = new Float32Array(dims[0] * dims[1] * dims[2]);
  let i = 0;
  for (let z = 0; z < dims[2]; z++)
    for (let y = 0; y < dims[1]; y++)
      for (let x = 0; x < dims[0]; x++) {
        const p = [x, y, z];
        const across = p.filter((_, a) => a !== long).reduce((s, c) => s + c, 0);
        out[i++] = Math.round(127 + 110 * Math.sin((2 * Math.PI * p[long]) / 997 + across / 3));
      }
  return out;
}

describe('a volume wider than 16384 voxels on an axis', () => {
  for (const { dims, long } of [
    { dims: [20000, 8, 6] as [number, number, number], long: 0 },
    { dims: [5, 6, 26730] as [number, number, number], long: 2 },
  ]) {
    gpuTest(`${dims.join('x')}: vtkMarchingCubes' triangles, area and bounds, out to the far end`, async ({ gpu }) => {
      const values = wideField(dims, long);
      const raw = join(work, `wide_${dims.join('x')}.raw`);
      writeFileSync(raw, values);
      const isovalues = [127.5, 200.25];
      const vtk = JSON.parse(runPython(VTK, [raw, 'float32', ...dims.map(String), isovalues.join(',')])) as [number, number][];
      const stream = await compressVolume(gpu.device, values, dims, 20);
      const iso = await Isosurface.create(gpu, stream, { memoryBudgetBytes: 256 * 2 ** 20, ...testKernelOptions });
      try {
        expect(sha256(await decodeVolume(gpu.device, stream))).toBe(sha256(values));
        for (const [i, v] of isovalues.entries()) {
          const stats = await iso.compute(v);
          const m = meshMetrics(await drawnSoup(iso));
          expect(stats.triangles).toBe(vtk[i][0]);
          expect(m.triangles).toBe(vtk[i][0]);
          expect(Math.abs(m.area / vtk[i][1] - 1)).toBeLessThan(0.005);
          // the wave crosses the whole long axis: the surface spans it
          expect(m.bbox!.min[long]).toBeLessThan(dims[long] / 100);
          expect(m.bbox!.max[long]).toBeGreaterThan(dims[long] - 1 - dims[long] / 100);
          for (let a = 0; a < 3; a++) expect(m.bbox!.max[a]).toBeLessThanOrEqual(dims[a] - 1);
        }
      } finally {
        iso.destroy();
        stream.destroy();
      }
    });
  }
});
