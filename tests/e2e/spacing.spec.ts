// Voxel size: a NRRD's spacings stretch the surface, its box and the PLY
// export (world coordinates = the CLI's voxel coordinates, which the unit
// tests hold to VTK's, times the spacing); Measure gives vtkMassProperties'
// area and volume of VTK's surface at that spacing, and the glTF export
// (read by pygltflib) the PLY's mesh with the surface colour; the user can
// correct the size (the volume follows), and the link carries what they set.
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { expect, test } from '@playwright/test';
import { parsePly } from '../../src/mc/ply.ts';
import { runPython } from '../helpers/python.ts';
import { runCli, SHARED_VOLUMES_DIR } from './cli.ts';
import { openApp, waitForFrames } from './page.ts';
import { acceptVolumeForm, loads, pageState, setIsovalue, SHARED_VOLUMES, waitForLoad } from './volume-page.ts';

const ISO = 80.37;

test('a NRRD with spacings is drawn and exported to scale; the size can be corrected and is kept in the link', async ({
  page,
  context,
}) => {
  await openApp(page);
  const before = await loads(page);
  await page.evaluate(async (url) => {
    const data = new Uint8Array(await (await fetch(url)).arrayBuffer());
    const header = new TextEncoder().encode(
      'NRRD0004\ntype: uint8\ndimension: 3\nsizes: 66 66 66\nencoding: raw\nspacings: 0.5 0.75 2\n\n',
    );
    const dt = new DataTransfer();
    dt.items.add(new File([header, data], 'neghip_aniso.nrrd'));
    document.getElementById('view')!.dispatchEvent(new DragEvent('drop', { dataTransfer: dt, bubbles: true, cancelable: true }));
  }, `${SHARED_VOLUMES}neghip_66x66x66_uint8.raw`);
  await acceptVolumeForm(page);
  await waitForLoad(page, before);
  expect((await pageState(page)).volume).toMatchObject({ kind: 'nrrd', dims: [66, 66, 66], spacing: [0.5, 0.75, 2] });
  await expect(page.locator('#spacing-z')).toHaveValue('2');
  await expect(page.locator('#spacing-note')).toHaveText('from the file');
  await setIsovalue(page, ISO);
  await waitForFrames(page, 1);

  // The exported mesh's box is the CLI's (same samples, same default rate 8) times the spacing.
  const cli = await runCli<{ isosurfaces: { triangles: number; bbox: { min: number[]; max: number[] } }[] }>([
    'extract',
    join(SHARED_VOLUMES_DIR, 'neghip_66x66x66_uint8.raw'),
    '--iso',
    String(ISO),
  ]);
  const [ref] = cli.isosurfaces;
  const [ply] = await Promise.all([page.waitForEvent('download'), page.locator('#save-ply').click()]);
  const mesh = parsePly(new Uint8Array(readFileSync((await ply.path())!)));
  expect(mesh.indices.length / 3).toBe(ref.triangles);
  expect(mesh.comments.join('\n')).toContain('world coordinates');
  const lo = [Infinity, Infinity, Infinity],
    hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < mesh.positions.length; i++) {
    lo[i % 3] = Math.min(lo[i % 3], mesh.positions[i]);
    hi[i % 3] = Math.max(hi[i % 3], mesh.positions[i]);
  }
  const spacing = [0.5, 0.75, 2];
  for (let a = 0; a < 3; a++) {
    expect(lo[a]).toBeCloseTo(ref.bbox.min[a] * spacing[a], 3);
    expect(hi[a]).toBeCloseTo(ref.bbox.max[a] * spacing[a], 3);
  }

  // Measure: VTK's surface of the same samples at the same spacing, measured by vtkMassProperties.
  const vtk = JSON.parse(
    runPython(
      `
import sys, json, numpy as np, vtk
from vtk.util import numpy_support
img = vtk.vtkImageData(); img.SetDimensions(66, 66, 66); img.SetSpacing(0.5, 0.75, 2)
img.GetPointData().SetScalars(numpy_support.numpy_to_vtk(np.fromfile(sys.argv[1], np.uint8).astype(np.float32), deep=True))
mc = vtk.vtkMarchingCubes(); mc.SetInputData(img); mc.SetValue(0, float(sys.argv[2])); mc.Update()
mp = vtk.vtkMassProperties(); mp.SetInputConnection(mc.GetOutputPort()); mp.Update()
print(json.dumps({'area': mp.GetSurfaceArea(), 'volume': mp.GetVolume()}))
`,
      [join(SHARED_VOLUMES_DIR, 'neghip_66x66x66_uint8.raw'), String(Math.fround(ISO))],
    ),
  );
  const measured = async () => {
    await page.locator('#measure-surface').click(); // clears window.zfpiso.measure until done
    await page.waitForFunction(() => window.zfpiso!.measure !== undefined);
    return (await page.evaluate(() => window.zfpiso!.measure))!;
  };
  const m = await measured();
  expect(m).toMatchObject({ closed: true, openEdges: 0, triangles: ref.triangles, voxelUnits: false });
  expect(Math.abs(m.area / vtk.area - 1)).toBeLessThan(1e-3);
  expect(Math.abs(m.enclosedVolume! / vtk.volume - 1)).toBeLessThan(1e-3);
  await expect(page.locator('#surface-measure')).toContainText('encloses');

  // glTF: the PLY's mesh, in the same world coordinates, with the surface's colour.
  const [glb] = await Promise.all([page.waitForEvent('download'), page.locator('#save-glb').click()]);
  expect(glb.suggestedFilename()).toMatch(/^neghip_aniso_iso80\.37\.glb$/);
  const read = JSON.parse(
    runPython(
      `
import sys, json, numpy as np
from pygltflib import GLTF2
g = GLTF2().load_binary(sys.argv[1])
p = g.meshes[0].primitives[0]
a = g.accessors[p.attributes.POSITION]
print(json.dumps({'meshes': len(g.meshes), 'vertices': a.count, 'indices': g.accessors[p.indices].count, 'min': a.min, 'max': a.max,
                  'color': g.materials[p.material].pbrMetallicRoughness.baseColorFactor, 'alpha': g.materials[p.material].alphaMode}))
`,
      [(await glb.path())!],
    ),
  );
  expect(read).toMatchObject({ meshes: 1, vertices: mesh.positions.length / 3, indices: mesh.indices.length, alpha: 'OPAQUE' });
  for (let a = 0; a < 3; a++) {
    expect(read.min[a]).toBeCloseTo(lo[a], 4);
    expect(read.max[a]).toBeCloseTo(hi[a], 4);
  }
  // the page's default front colour (0.86, 0.8, 0.7) in linear light
  expect(read.color[0]).toBeCloseTo(((0.86 + 0.055) / 1.055) ** 2.4, 5);

  // Correcting the size refits the view and goes into the link.
  const camBefore = await page.evaluate(() => window.zfpiso!.camera!());
  await page.locator('#spacing-z').fill('1');
  await page.locator('#spacing-z').press('Enter');
  await expect.poll(async () => (await pageState(page)).volume?.spacing).toEqual([0.5, 0.75, 1]);
  await expect(page.locator('#spacing-note')).toHaveText('set here');
  const camAfter = await page.evaluate(() => window.zfpiso!.camera!());
  expect(camAfter.target[2]).toBeCloseTo(camBefore.target[2] / 2, 3);
  await page.waitForFunction(() => location.hash.includes('vox=0.5,0.75,1'));
  // half the voxel depth: half the volume, the same triangles
  const halved = await measured();
  expect(halved.triangles).toBe(m.triangles);
  expect(halved.enclosedVolume! / m.enclosedVolume!).toBeCloseTo(0.5, 9);

  // A bad size is refused and the previous one shown again.
  await page.locator('#spacing-x').fill('0');
  await page.locator('#spacing-x').press('Enter');
  await expect(page.locator('#spacing-note')).toContainText('positive');
  await expect(page.locator('#spacing-x')).toHaveValue('0.5');
  expect((await pageState(page)).volume?.spacing).toEqual([0.5, 0.75, 1]);

  // A link with a voxel size applies it over the volume's own (here the built-in one's 1, 1, 1).
  const linked = await context.newPage();
  await openApp(linked, '/#iso=0.5&vox=1,1,3');
  expect((await pageState(linked)).volume?.spacing).toEqual([1, 1, 3]);
  await expect(linked.locator('#spacing-note')).toHaveText('set by the link');
  await expect(linked.locator('#spacing-z')).toHaveValue('3');
});
