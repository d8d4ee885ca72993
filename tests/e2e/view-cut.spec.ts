// A store refined by the view (src/store/view/): `?store=...#cut=1` shows
// the coarsest level at once, then each region at the level the camera
// needs; zooming in with the wheel brings level 0 where the camera looks,
// frames keep being drawn while chunks arrive, the panel shows the cut
// (chunks on screen per level, tolerance, tint), and the link keeps it.
import { execFileSync } from 'node:child_process';
import { mkdirSync, rmSync } from 'node:fs';
import { join } from 'node:path';
import { expect, type Page, test } from '@playwright/test';
import { E2E_STORES_DIR } from './cli.ts';
import { openApp, watchErrors } from './page.ts';

const NAME = 'gen-view-e2e.zarr';

interface CutState {
  done: boolean;
  cut: {
    tolerancePx: number;
    tint: boolean;
    final: boolean;
    levels: { level: number; drawn: number; regions: number; triangles: number }[];
  } | null;
  gpu: { total: number; budget: number };
}
const storeState = (page: Page) => page.evaluate(() => (window as unknown as { zfpisoStore: unknown }).zfpisoStore) as Promise<CutState>;
const settled = (page: Page) =>
  page.waitForFunction(
    () => {
      const s = (window as unknown as { zfpisoStore?: CutState }).zfpisoStore;
      return s?.done === true && s.cut?.final === true;
    },
    null,
    { timeout: 240_000 },
  );

test.beforeAll(() => {
  const out = join(E2E_STORES_DIR, NAME);
  rmSync(out, { recursive: true, force: true });
  mkdirSync(E2E_STORES_DIR, { recursive: true });
  execFileSync(
    process.execPath,
    [join(E2E_STORES_DIR, '../../scripts/convert.mjs'), 'gen:256x256x256', '--out', out, '--chunk', '32', '--rate', '8', '--quiet'],
    { timeout: 600_000 },
  );
});

test('cut=1: wheel zoom brings level 0 where the camera looks; frames go on while chunks arrive; panel and link show the cut', async ({
  page,
}) => {
  test.setTimeout(400_000);
  const errors = watchErrors(page);
  // a coarse tolerance: the fitted view needs no level 0, a close one does
  await openApp(page, `/?store=/stores/${NAME}#iso=0.437&cut=1&tol=6&tint=1`);
  await settled(page);
  const fitted = await storeState(page);
  expect(fitted.cut!.tolerancePx).toBe(6);
  expect(fitted.cut!.tint).toBe(true);
  expect(fitted.cut!.levels[0].drawn).toBe(0);
  expect(fitted.gpu.total).toBeLessThanOrEqual(fitted.gpu.budget);
  await expect(page.locator('#store-section input[data-cut="cut"]')).toBeChecked();
  await expect(page.locator('#store-section input[data-cut="tolerancePx"]')).toHaveValue('6');
  await expect(page.locator('#store-section th', { hasText: 'on screen' })).toHaveCount(1);

  // zoom in with the wheel over the view: the eye comes close to the volume's +x +y +z corner (the Fit looks from there), still outside
  const view = page.locator('#view');
  const box = (await view.boundingBox())!;
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  const framesBefore = await page.evaluate(() => window.zfpiso!.framesDrawn());
  for (let i = 0; i < 3; i++) {
    await page.mouse.wheel(0, -240);
    await page.waitForTimeout(60);
  }
  // frames keep coming while the finer chunks stream in
  await page.waitForFunction((n) => window.zfpiso!.framesDrawn() > n + 3, framesBefore, { timeout: 60_000 });
  await page.waitForFunction(() => ((window as unknown as { zfpisoStore?: CutState }).zfpisoStore?.cut?.levels[0].drawn ?? 0) > 0, null, {
    timeout: 240_000,
  });
  await settled(page);
  const zoomed = await storeState(page);
  expect(zoomed.cut!.levels[0].drawn).toBeGreaterThan(0);
  // every region at one level: the regions on screen are the cut's leaves
  expect(zoomed.cut!.levels.reduce((a, l) => a + l.regions, 0)).toBeGreaterThan(0);
  expect(zoomed.gpu.total).toBeLessThanOrEqual(zoomed.gpu.budget);
  await expect(page.locator('#store-section td[data-k="on-screen"]').first()).toHaveText(String(zoomed.cut!.levels[0].drawn));
  // the link keeps the refinement and the canvas
  await page.waitForTimeout(400);
  const hash = await page.evaluate(() => location.hash);
  expect(hash).toContain('cut=1');
  expect(hash).toContain('tol=6');
  expect(hash).toMatch(/px=\d+,\d+/);

  // the slider at its minimum (issue 36: the page threw and stopped drawing when no chunk held the surface):
  // the cut settles, nothing at that isovalue is drawn from a stale surface, frames go on, no page error
  await page.locator('#iso-slider').focus();
  await page.keyboard.press('Home');
  await settled(page);
  const framesAtMin = await page.evaluate(() => window.zfpiso!.framesDrawn());
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  // frames are drawn on demand: each wheel step asks for one (the page threw in every frame before)
  for (let i = 0; i < 4; i++) {
    await page.mouse.wheel(0, 60);
    await page.waitForTimeout(80);
  }
  await page.waitForFunction((n) => window.zfpiso!.framesDrawn() > n + 1, framesAtMin, { timeout: 60_000 });
  // and back to a surface
  await page.locator('#iso-value').fill('0.437');
  await page.locator('#iso-value').press('Enter');
  await settled(page);
  expect(errors).toEqual([]);
});

test('cut=1 on a store 20480 voxels wide (past 16384): 8 wheel steps toward it, the page stays responsive and draws level 0 where it looks', async ({
  page,
}) => {
  test.setTimeout(400_000);
  const wide = 'gen-wide-e2e.zarr';
  const out = join(E2E_STORES_DIR, wide);
  rmSync(out, { recursive: true, force: true });
  execFileSync(
    process.execPath,
    [join(E2E_STORES_DIR, '../../scripts/convert.mjs'), 'gen:20480x32x32', '--out', out, '--chunk', '32', '--rate', '2', '--quiet'],
    { timeout: 600_000 },
  );
  const errors = watchErrors(page);
  await openApp(page, `/?store=/stores/${wide}#iso=0.5&cut=1`);
  await settled(page);
  // the coarsest levels are one voxel thick (640 x 1 x 1 ...): no cell, no surface; the cut starts where a surface can be
  const fitted = await storeState(page);
  expect(fitted.cut!.levels.reduce((a, l) => a + l.triangles, 0)).toBeGreaterThan(0);
  expect(fitted.cut!.levels.slice(5).every((l) => l.regions === 0)).toBe(true);
  await expect(page.locator('#messages')).not.toContainText(/cannot be shown/);
  const view = page.locator('#view');
  const box = (await view.boundingBox())!;
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  // the wheel steps that took the tab down when level 0 could not be drawn
  for (let i = 0; i < 8; i++) {
    await page.mouse.wheel(0, -240);
    await page.waitForTimeout(60);
  }
  const frames = await page.evaluate(() => window.zfpiso!.framesDrawn());
  await page.mouse.wheel(0, 30);
  await page.waitForFunction((n) => window.zfpiso!.framesDrawn() > n, frames, { timeout: 60_000 });
  // closer still, until a voxel of level 0 spans more than the tolerance (the bar is 32 voxels across)
  for (let i = 0; i < 8; i++) {
    await page.mouse.wheel(0, -240);
    await page.waitForTimeout(60);
  }
  await page.waitForFunction(() => ((window as unknown as { zfpisoStore?: CutState }).zfpisoStore?.cut?.levels[0].drawn ?? 0) > 0, null, {
    timeout: 240_000,
  });
  await settled(page);
  const zoomed = await storeState(page);
  expect(zoomed.cut!.levels[0].drawn).toBeGreaterThan(0);
  expect(zoomed.gpu.total).toBeLessThanOrEqual(zoomed.gpu.budget);
  expect(errors).toEqual([]);
});
