// The serial TS marching cubes against VTK's vtkMarchingCubes on every volume and
// isovalue of shared/data/reference/mc.json (computed there with VTK 9.7.2).
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, test } from 'vitest';
import { meshMetrics } from '../../../src/mc/mesh-metrics.ts';
import { marchingCubes } from '../../../src/mc/serial-mc.ts';
import { loadMcReference, loadMcVolume } from './reference.ts';

const reference = loadMcReference();
let cacheDir = '';
beforeAll(() => {
  cacheDir = mkdtempSync(join(tmpdir(), 'zfpiso-mc-'));
});
afterAll(() => rmSync(cacheDir, { recursive: true, force: true }));

/** Distinct vertices of a soup (VTK merges them: its point count = crossed edges). */
function distinctVertices(p: Float32Array): number {
  const seen = new Set<string>();
  for (let v = 0; v < p.length; v += 3) seen.add(`${p[v]},${p[v + 1]},${p[v + 2]}`);
  return seen.size;
}

test('mc.json covers the shared volumes', () => {
  expect(reference.volumes.length).toBeGreaterThanOrEqual(9);
  for (const v of reference.volumes) expect(v.isosurfaces.length).toBe(5);
});

for (const volume of reference.volumes) {
  describe(volume.file, () => {
    let values: Float32Array;
    beforeAll(() => {
      values = loadMcVolume(volume, cacheDir);
    });
    for (const s of volume.isosurfaces) {
      test(`iso ${s.iso_nominal}: same triangle count as vtkMarchingCubes, area and bbox`, () => {
        const vtk = s.vtkMarchingCubes;
        const { positions, triangleCount } = marchingCubes(values, volume.dims_xyz, s.iso);
        const m = meshMetrics(positions);
        expect(triangleCount).toBe(vtk.triangles);
        expect(m.triangles).toBe(vtk.triangles);
        expect(m.degenerate).toBe(vtk.degenerate_triangles);
        // Only float32 rounding separates our vertices from VTK's: about 1e-8 relative.
        expect(Math.abs(m.area - vtk.area) / vtk.area).toBeLessThan(1e-6);
        for (let a = 0; a < 3; a++) {
          expect(Math.abs(m.bbox!.min[a] - vtk.bbox!.min[a])).toBeLessThan(1e-4);
          expect(Math.abs(m.bbox!.max[a] - vtk.bbox!.max[a])).toBeLessThan(1e-4);
        }
        // One vertex per crossed edge, computed alike by every cell sharing it.
        if (positions.length < 1_500_000) expect(distinctVertices(positions)).toBe(vtk.points);
      });
    }
  });
}
