// Picking: with "Pick points" on, a click on the surface gives the point
// (voxel and world) and the volume's value there, which equals NumPy's
// trilinear interpolation of zfpy's decode of the file at that point and
// lies near the isovalue (the point is on the surface); a second click the
// distance; a click on the background picks nothing; a see-through surface
// is picked where the opaque one was.
import { join } from 'node:path';
import { expect, test } from '@playwright/test';
import { runPython } from '../helpers/python.ts';
import { SHARED_VOLUMES_DIR } from './cli.ts';
import { nonBackgroundFraction, openApp, waitForFrames } from './page.ts';

const FILE = 'hydrogen_atom_128x128x128_float32.rate8.zfp';

test('pick two points on the surface: coordinates, values as NumPy over zfpy, the distance', async ({ page }) => {
  await openApp(page, `/?url=/data/volumes/${FILE}#iso=20`);
  await waitForFrames(page, 2);
  await page.locator('#pick-points').check();
  const view = page.locator('#view');
  const box = (await view.boundingBox())!;
  const picks = () => page.evaluate(() => window.zfpiso!.picks);
  // the background (a corner) picks nothing
  await view.click({ position: { x: 3, y: 3 } });
  await waitForFrames(page, 2);
  expect(await picks()).toBeUndefined();
  await view.click({ position: { x: box.width / 2, y: box.height / 2 } });
  await page.waitForFunction(() => window.zfpiso!.picks?.points.length === 1);
  await view.click({ position: { x: box.width / 2 + 25, y: box.height / 2 - 10 } });
  await page.waitForFunction(() => window.zfpiso!.picks?.points.length === 2);
  const { points, distance } = (await picks())!;
  const values = JSON.parse(
    runPython(
      `
import sys, json, zfpy, numpy as np
v = zfpy.decompress_numpy(open(sys.argv[1], 'rb').read()).astype(np.float64)
out = []
for p in json.loads(sys.argv[2]):
    lo = [min(max(int(np.floor(p[a])), 0), 126) for a in range(3)]
    f = [p[a] - lo[a] for a in range(3)]
    out.append(sum(np.prod([f[a] if (k >> a) & 1 else 1 - f[a] for a in range(3)]) * v[lo[2] + ((k >> 2) & 1), lo[1] + ((k >> 1) & 1), lo[0] + (k & 1)] for k in range(8)))
print(json.dumps(out))
`,
      [join(SHARED_VOLUMES_DIR, FILE), JSON.stringify(points.map((p) => p.voxel))],
    ),
  );
  points.forEach((p, i) => {
    expect(p.value!).toBeCloseTo(values[i], 3);
    // on the surface: the interpolant there is near the isovalue (MC and trilinear surfaces differ inside cells)
    expect(Math.abs(p.value! - 20)).toBeLessThan(3);
    for (let a = 0; a < 3; a++) expect(p.voxel[a]).toBeGreaterThanOrEqual(0);
  });
  expect(distance).toBeCloseTo(Math.hypot(...[0, 1, 2].map((a) => points[0].world[a] - points[1].world[a])), 9);
  expect(distance!).toBeGreaterThan(1);
  await expect(page.locator('#pick-info')).toContainText('distance');

  // see-through (depth peeled): the same pixel picks the same point
  await page.locator('#surface-list li').nth(0).locator('input[type=range]').fill('0.5');
  await waitForFrames(page, 2);
  await view.click({ position: { x: box.width / 2, y: box.height / 2 } });
  await page.waitForFunction(() => window.zfpiso!.picks?.points.length === 1);
  const again = (await picks())!.points[0];
  for (let a = 0; a < 3; a++) expect(again.voxel[a]).toBeCloseTo(points[0].voxel[a], 3);
});

test('draw=rays: the surface ray cast in the block cache; a picked point lies on the trilinear surface exactly', async ({ page }) => {
  await openApp(page, `/?url=/data/volumes/${FILE}#iso=20&draw=rays`);
  await waitForFrames(page, 2);
  expect(await page.evaluate(() => window.zfpiso!.draw)).toBe('rays');
  await expect(page.locator('#draw-mode')).toHaveValue('rays');
  const rays = await nonBackgroundFraction(page);
  await page.locator('#pick-points').check();
  const view = page.locator('#view');
  const box = (await view.boundingBox())!;
  await view.click({ position: { x: box.width / 2 + 25, y: box.height / 2 - 10 } });
  await page.waitForFunction(() => window.zfpiso!.picks?.points.length === 1);
  const onRays = (await page.evaluate(() => window.zfpiso!.picks!.points[0]))!;
  // the rays stop at the interpolant's crossing: the value there is the isovalue (the depth buffer's float32 aside)
  expect(Math.abs(onRays.value! - 20)).toBeLessThan(0.05);
  // triangles again: the same picture within a few pixels' worth, the same point within a voxel
  await page.locator('#draw-mode').selectOption('mesh');
  await waitForFrames(page, 2);
  expect(Math.abs((await nonBackgroundFraction(page)) - rays)).toBeLessThan(0.01 * rays + 0.002);
  await page.locator('#pick-points').uncheck();
  await page.locator('#pick-points').check();
  await view.click({ position: { x: box.width / 2 + 25, y: box.height / 2 - 10 } });
  await page.waitForFunction(() => window.zfpiso!.picks?.points.length === 1);
  const onMesh = (await page.evaluate(() => window.zfpiso!.picks!.points[0]))!;
  expect(Math.hypot(...[0, 1, 2].map((a) => onMesh.voxel[a] - onRays.voxel[a]))).toBeLessThan(1);
  await page.waitForFunction(() => !location.hash.includes('draw='));
  await page.locator('#draw-mode').selectOption('rays');
  await page.waitForFunction(() => location.hash.includes('draw=rays'));
});
