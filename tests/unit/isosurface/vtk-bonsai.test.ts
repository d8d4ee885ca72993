// The two bonsai entries of mc.json (256^3: the rate-4 file as is, and the
// precision-8 decode re-compressed losslessly at rate 8) against
// vtkMarchingCubes; see vtk.test.ts.
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe } from 'vitest';
import { gpuTest } from '../../helpers/gpu.ts';
import { loadMcReference } from '../mc/reference.ts';
import { checkAgainstVtk } from './vtk-reference.ts';

const bonsai = loadMcReference().volumes.filter((v) => v.file.includes('bonsai'));
let cacheDir = '';
beforeAll(() => {
  cacheDir = mkdtempSync(join(tmpdir(), 'zfpiso-vtk-'));
});
afterAll(() => rmSync(cacheDir, { recursive: true, force: true }));

describe('bonsai isosurfaces = vtkMarchingCubes', () => {
  for (const v of bonsai) {
    gpuTest(v.file, async ({ gpu }) => {
      const log = await checkAgainstVtk(gpu, [v], cacheDir);
      console.log(log.join('\n'));
    });
  }
});
