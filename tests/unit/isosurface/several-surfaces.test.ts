// Several surfaces over one pipeline, as the page keeps them
// (src/app/surfaces/): each surface computed in turn and copied
// (Isosurface.newCopy / copyInto) has exactly vtkMarchingCubes' triangles at
// its isovalue (mc.json), the copies keep them while the live surface moves,
// and the cache is shared: the blocks decoded for all of them are the union
// of their active blocks, each decoded once.
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { describe, expect } from 'vitest';
import { Isosurface } from '../../../src/isosurface/isosurface.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { loadMcReference } from '../mc/reference.ts';
import { prepareVolume } from './vtk-reference.ts';

describe('several surfaces over one cache', () => {
  gpuTest('neghip: copies keep VTK triangles; decoded blocks = the union of active blocks', async ({ gpu }) => {
    const entry = loadMcReference().volumes.find((v) => v.file === 'volumes/neghip_66x66x66_uint8.raw')!;
    const cacheDir = mkdtempSync(join(tmpdir(), 'several-'));
    const { stream } = await prepareVolume(gpu.device, entry, cacheDir);
    const iso = await Isosurface.create(gpu, stream, { memoryBudgetBytes: 256 * 2 ** 20 });
    const surfaces = entry.isosurfaces.slice(0, 3);
    expect(surfaces.length).toBe(3);
    const copies = [];
    const union = new Set<number>();
    let decoded = 0;
    for (const s of surfaces) {
      const stats = await iso.compute(s.iso);
      decoded += stats.newBlocks;
      for (const id of (await iso.readBlockTriangles()).ids) union.add(id);
      const copy = iso.newCopy();
      iso.copyInto(copy);
      copies.push(copy);
      expect(stats.triangles).toBe(s.vtkMarchingCubes.triangles);
    }
    // each block any of them needs was decoded once
    expect(decoded).toBe(union.size);
    // the live surface moves on; every copy still draws its own surface
    await iso.compute(surfaces[0].iso + 0.25);
    copies.forEach((c, i) => expect(c.triangles).toBe(surfaces[i].vtkMarchingCubes.triangles));
    const mesh = await copies[2].readMesh(stream.info.dims);
    expect(mesh.indices.length / 3).toBe(surfaces[2].vtkMarchingCubes.triangles);
    expect(mesh.vertices.length / 3).toBe(surfaces[2].vtkMarchingCubes.points);
    for (const c of copies) c.destroy();
    iso.destroy();
    stream.destroy();
    rmSync(cacheDir, { recursive: true, force: true });
  });
});
