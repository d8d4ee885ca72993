// What a user sees first and does first: the built-in volume as a shaded
// surface, and the camera (orbit, pan, zoom, reset, fit).
import { expect, test, type Page } from '@playwright/test';
import { nonBackgroundFraction, openApp, waitForFrames, watchErrors } from './page.ts';
import { runCli } from './cli.ts';
import { trianglesShown } from './volume-page.ts';

async function canvasPixels(page: Page): Promise<Buffer> {
  await waitForFrames(page, 1);
  // Only the rendering: hide the readouts over the view (the frame rate changes).
  const hide = await page.addStyleTag({ content: '#hud, #view-tools { visibility: hidden !important; }' });
  // Two animation frames: the last camera change has been drawn.
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  const png = await page.locator('#view').screenshot();
  await hide.evaluate((el) => (el as HTMLElement).remove());
  return png;
}

test("the page opens on the built-in volume with a shaded surface and the CLI's triangle count", async ({ page }) => {
  const errors = watchErrors(page);
  const started = Date.now();
  await openApp(page);
  // Within seconds, even on SwiftShader.
  expect(Date.now() - started).toBeLessThan(30_000);
  // The CLI computes the same volume (generated, compressed at the same rate) headless on Dawn.
  const cli = runCli<{ isosurfaces: { iso: number; triangles: number }[] }>(['extract', 'default', '--iso', '0.5']);
  const state = await page.evaluate(() => ({ volume: window.zfpiso!.volume, stats: window.zfpiso!.stats }));
  expect(state.volume?.kind).toBe('default');
  expect(state.volume?.dims).toEqual([128, 128, 128]);
  expect(state.stats?.isovalue).toBeCloseTo(0.5, 6);
  expect(state.stats?.triangles).toBeGreaterThan(10_000);
  await waitForFrames(page, 1);
  expect(await nonBackgroundFraction(page)).toBeGreaterThan(0.1);
  expect(await trianglesShown(page)).toBe(state.stats!.triangles);
  const headless = (await cli).isosurfaces[0];
  expect(headless.iso).toBe(Math.fround(0.5));
  expect(await trianglesShown(page)).toBe(headless.triangles);
  await expect(page.locator('#volume-info dd[data-key="dims"]')).toHaveText('128 × 128 × 128');
  await expect(page.locator('#iso-value')).toHaveValue('0.5000');
  await expect(page.locator('#hud')).toContainText('triangles');
  expect(errors).toEqual([]);
});

test('dragging, panning and zooming change the view; R and double-click reset it; F fits', async ({ page }) => {
  await openApp(page);
  const view = page.locator('#view');
  const home = await canvasPixels(page);
  const homeCamera = await page.evaluate(() => window.zfpiso!.camera!());
  const box = (await view.boundingBox())!;
  const cx = box.x + box.width / 2,
    cy = box.y + box.height / 2;

  // Orbit
  await page.mouse.move(cx, cy);
  await page.mouse.down();
  await page.mouse.move(cx + 120, cy + 40, { steps: 6 });
  await page.mouse.up();
  const orbited = await canvasPixels(page);
  expect(orbited.equals(home)).toBe(false);
  const cam1 = await page.evaluate(() => window.zfpiso!.camera!());
  expect(cam1.rotation).not.toEqual(homeCamera.rotation);

  // R resets to exactly the home view.
  await page.keyboard.press('r');
  expect((await canvasPixels(page)).equals(home)).toBe(true);

  // Shift-drag pans (the target moves, the rotation stays).
  await page.keyboard.down('Shift');
  await page.mouse.move(cx, cy);
  await page.mouse.down();
  await page.mouse.move(cx + 80, cy, { steps: 4 });
  await page.mouse.up();
  await page.keyboard.up('Shift');
  const cam2 = await page.evaluate(() => window.zfpiso!.camera!());
  expect(cam2.rotation).toEqual(homeCamera.rotation);
  expect(cam2.target).not.toEqual(homeCamera.target);

  // Wheel zooms.
  await page.mouse.wheel(0, -400);
  const cam3 = await page.evaluate(() => window.zfpiso!.camera!());
  expect(cam3.distance).toBeLessThan(cam2.distance);
  expect((await canvasPixels(page)).equals(home)).toBe(false);

  // F: whole volume in view again, same direction.
  await page.locator('#fit-view').click();
  const cam4 = await page.evaluate(() => window.zfpiso!.camera!());
  expect(cam4.target).toEqual(homeCamera.target);
  expect(cam4.distance).toBeCloseTo(homeCamera.distance, 6);

  // Double-click resets too.
  await page.mouse.move(cx, cy);
  await page.mouse.down();
  await page.mouse.move(cx - 90, cy - 60, { steps: 5 });
  await page.mouse.up();
  await view.dblclick();
  expect((await canvasPixels(page)).equals(home)).toBe(true);
});

test.describe('on a touch screen', () => {
  test.use({ hasTouch: true });

  test('one finger rotates; two fingers pinch to zoom and move together to pan', async ({ page }) => {
    await openApp(page);
    const box = (await page.locator('#view').boundingBox())!;
    const cx = box.x + box.width / 2,
      cy = box.y + box.height / 2;
    // Chromium delivers touch moves aligned to animation frames, after the protocol call returns:
    // read the camera once it has stopped changing from one pair of frames to the next.
    const camera = () =>
      page.evaluate(async () => {
        const frames = () => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
        let last = '';
        for (;;) {
          await frames();
          const now = window.zfpiso!.camera!();
          if (JSON.stringify(now) === last) return now;
          last = JSON.stringify(now);
        }
      });
    // Chromium's own touch input (through the DevTools protocol), so the page gets real touch pointer events.
    const cdp = await page.context().newCDPSession(page);
    const touch = async (type: 'touchStart' | 'touchMove' | 'touchEnd', points: [number, number][]) => {
      await cdp.send('Input.dispatchTouchEvent', { type, touchPoints: points.map(([x, y], id) => ({ x, y, id })) });
    };
    const home = await camera();

    await touch('touchStart', [[cx, cy]]);
    for (let i = 1; i <= 5; i++) await touch('touchMove', [[cx + 20 * i, cy]]);
    await touch('touchEnd', []);
    const rotated = await camera();
    expect(rotated.rotation).not.toEqual(home.rotation);
    expect(rotated.distance).toBeCloseTo(home.distance, 6);

    // Spread two fingers apart: closer, the rotation kept.
    await touch('touchStart', [
      [cx - 40, cy],
      [cx + 40, cy],
    ]);
    for (let i = 1; i <= 5; i++)
      await touch('touchMove', [
        [cx - 40 - 16 * i, cy],
        [cx + 40 + 16 * i, cy],
      ]);
    const pinched = await camera();
    expect(pinched.distance).toBeLessThan(rotated.distance * 0.6);
    expect(pinched.rotation).toEqual(rotated.rotation);
    // Both fingers move together: a pan (the target moves; distance and rotation stay).
    for (let i = 1; i <= 5; i++)
      await touch('touchMove', [
        [cx - 120 + 10 * i, cy + 10 * i],
        [cx + 120 + 10 * i, cy + 10 * i],
      ]);
    await touch('touchEnd', []);
    const panned = await camera();
    expect(panned.target).not.toEqual(pinched.target);
    expect(panned.distance).toBeCloseTo(pinched.distance, 6);
    expect(panned.rotation).toEqual(rotated.rotation);
  });
});
