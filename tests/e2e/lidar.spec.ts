// The LIDAR page: the shared LAZ file decoded by the LASzip Wasm module and
// drawn as splats; colour modes; a bad file; a generated cloud.
import { fileURLToPath } from 'node:url';
import { expect, test } from '@playwright/test';
import { nonBackgroundFraction, openApp, waitForFrames, watchErrors } from './page.ts';

const autzen = fileURLToPath(new URL('../../../shared/data/las/lazperf_autzen_trim.laz', import.meta.url));

const lidar = (page: import('@playwright/test').Page) => page.evaluate(() => window.lidar!);

test('the shared LAZ file shows as 110,000 points, in every colour mode', async ({ page }) => {
  const errors = watchErrors(page);
  await openApp(page, '/lidar.html');
  await page.setInputFiles('#file-input', autzen);
  await page.waitForFunction(() => window.lidar?.loadMs !== undefined, null, { timeout: 120_000 });
  const s = await lidar(page);
  expect(s.pointCount).toBe(110_000);
  expect(s.source).toBe('lazperf_autzen_trim.laz');
  await expect(page.locator('#cloud-info dd[data-key="points"]')).toHaveText('110,000');
  await expect(page.locator('#cloud-info dd[data-key="format"]')).toHaveText('LAS 1.2, point format 3, LAZ');
  await expect(page.locator('#cloud-info dd[data-key="load time"]')).toContainText(/\d/);
  await expect(page.locator('#view-badge')).toContainText('110,000 points');
  await waitForFrames(page, 2);
  const rgbCover = await nonBackgroundFraction(page);
  expect(rgbCover).toBeGreaterThan(0.05);

  // Classification: a legend of the classes present, and a redraw.
  const before = await page.evaluate(() => window.zfpiso!.framesDrawn());
  await page.selectOption('#color-mode', 'classification');
  await expect(page.locator('#legend .legend label').first()).toBeVisible();
  await expect(page.locator('#legend')).toContainText('ground');
  await page.waitForFunction((n) => window.zfpiso!.framesDrawn() > n, before);
  // Bigger, square splats cover more of the view.
  await page.getByText('Square', { exact: true }).click();
  await expect(page.locator('input[name="shape"][value="square"]')).toBeChecked();
  await page.locator('#point-size').fill('8');
  await expect(page.locator('#point-size-value')).toHaveText('8 px');
  // The viewer draws on the next animation frame: let two pass.
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  expect(await nonBackgroundFraction(page)).toBeGreaterThan(rgbCover);
  expect(errors).toEqual([]);
});

test('a broken file gives a message naming it, and the page keeps working', async ({ page }) => {
  await openApp(page, '/lidar.html');
  await page.setInputFiles('#file-input', {
    name: 'broken.laz',
    mimeType: 'application/octet-stream',
    buffer: Buffer.from('LASF but not really a point cloud'),
  });
  await expect(page.locator('#messages .message')).toContainText(
    'broken.laz: truncated file: 33 bytes, shorter than a LAS header (227 bytes)',
  );
  await expect(page.locator('body')).toHaveAttribute('data-status', 'ready');
  expect((await lidar(page)).loading).toBe(false);
});

test('a generated cloud (?generate=N) is drawn', async ({ page }) => {
  await openApp(page, '/lidar.html?generate=60000');
  await page.waitForFunction(() => window.lidar?.loadMs !== undefined, null, { timeout: 120_000 });
  expect((await lidar(page)).pointCount).toBe(60_000);
  await waitForFrames(page, 2);
  expect(await nonBackgroundFraction(page)).toBeGreaterThan(0.05);
});
