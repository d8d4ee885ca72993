// Every volume and isovalue of shared/data/reference/mc.json: triangle count
// equal to vtkMarchingCubes' (the classic table), area within 0.5% and
// bounding box within one voxel (observed: ~1e-5 and ~0.002 voxel, the
// vertex quantization). Bonsai (256^3) is in vtk-bonsai.test.ts so the two
// files run side by side.
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, test } from 'vitest';
import { gpuTest } from '../../helpers/gpu.ts';
import { loadMcReference, type McVolume } from '../mc/reference.ts';
import { checkAgainstVtk, groupByData } from './vtk-reference.ts';

const volumes = loadMcReference().volumes;
let cacheDir = '';
beforeAll(() => {
  cacheDir = mkdtempSync(join(tmpdir(), 'zfpiso-vtk-'));
});
afterAll(() => rmSync(cacheDir, { recursive: true, force: true }));

/** What the figures describe: the decoded hash where given, else the file. */
const dataKey = (v: McVolume) => v.decoded_sha256 ?? v.file_sha256;

test('mc.json: every volume is covered here or in vtk-bonsai.test.ts', () => {
  expect(volumes.length).toBeGreaterThanOrEqual(9);
  const bonsai = volumes.filter((v) => v.file.includes('bonsai'));
  expect(bonsai.length).toBe(2);
});

describe('isosurfaces of the shared volumes = vtkMarchingCubes', () => {
  for (const group of groupByData(
    volumes.filter((v) => !v.file.includes('bonsai')),
    dataKey,
  )) {
    gpuTest(group.map((v) => v.file).join(' = '), async ({ gpu }) => {
      const log = await checkAgainstVtk(gpu, group, cacheDir);
      console.log(log.join('\n'));
    });
  }
});
