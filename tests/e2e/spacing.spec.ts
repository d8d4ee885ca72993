// Voxel size: a NRRD's spacings stretch the surface, its box and the PLY
// export (world coordinates = the CLI's voxel coordinates, which the unit
// tests hold to VTK's, times the spacing); the user can correct the size,
// and the link carries what they set.
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { expect, test } from '@playwright/test';
import { parsePly } from '../../src/mc/ply.ts';
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

  // Correcting the size refits the view and goes into the link.
  const camBefore = await page.evaluate(() => window.zfpiso!.camera!());
  await page.locator('#spacing-z').fill('1');
  await page.locator('#spacing-z').press('Enter');
  await expect.poll(async () => (await pageState(page)).volume?.spacing).toEqual([0.5, 0.75, 1]);
  await expect(page.locator('#spacing-note')).toHaveText('set here');
  const camAfter = await page.evaluate(() => window.zfpiso!.camera!());
  expect(camAfter.target[2]).toBeCloseTo(camBefore.target[2] / 2, 3);
  await page.waitForFunction(() => location.hash.includes('vox=0.5,0.75,1'));

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
