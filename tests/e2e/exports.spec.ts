// What a user takes away: the view as PNG, the surface as a binary PLY mesh
// (every triangle of the panel's count, in voxel coordinates inside the
// volume), and a link that reopens the same isovalue and camera.
import { readFileSync } from 'node:fs';
import { expect, test } from '@playwright/test';
import { parsePly } from '../../src/mc/ply.ts';
import { encodeViewState } from '../../src/app/url-state.ts';
import { openApp, waitForFrames } from './page.ts';
import { setIsovalue, trianglesShown } from './volume-page.ts';

test('PNG screenshot and PLY export of the current surface', async ({ page }) => {
  await openApp(page);
  await setIsovalue(page, 0.43);
  await waitForFrames(page, 1);

  const [png] = await Promise.all([page.waitForEvent('download'), page.locator('#save-png').click()]);
  expect(png.suggestedFilename()).toBe('default_iso0.43.png');
  const bytes = readFileSync((await png.path())!);
  expect([...bytes.subarray(0, 8)]).toEqual([137, 80, 78, 71, 13, 10, 26, 10]);
  // The image is the canvas at its pixel size, and shows the surface.
  const size = await page.locator('#view').evaluate((c: HTMLCanvasElement) => [c.width, c.height]);
  expect([bytes.readUInt32BE(16), bytes.readUInt32BE(20)]).toEqual(size);
  const cover = await page.evaluate(
    async (data) => {
      const bitmap = await createImageBitmap(new Blob([new Uint8Array(data)], { type: 'image/png' }));
      const c = new OffscreenCanvas(bitmap.width, bitmap.height);
      const g = c.getContext('2d')!;
      g.drawImage(bitmap, 0, 0);
      const d = g.getImageData(0, 0, c.width, c.height).data;
      let n = 0;
      for (let i = 0; i < d.length; i += 4) if (Math.abs(d[i] - d[0]) + Math.abs(d[i + 1] - d[1]) + Math.abs(d[i + 2] - d[2]) > 12) n++;
      return n / (d.length / 4);
    },
    [...bytes],
  );
  expect(cover).toBeGreaterThan(0.1);

  // The P key saves too.
  await page.locator('#view').focus();
  const [png2] = await Promise.all([page.waitForEvent('download'), page.keyboard.press('p')]);
  expect(png2.suggestedFilename()).toMatch(/\.png$/);

  const [ply] = await Promise.all([page.waitForEvent('download'), page.locator('#save-ply').click()]);
  expect(ply.suggestedFilename()).toBe('default_iso0.43.ply');
  await expect(page.locator('#messages .message.info').last()).toContainText(
    `Exported ${(await trianglesShown(page)).toLocaleString('en-US')} triangles`,
  );
  const mesh = parsePly(new Uint8Array(readFileSync((await ply.path())!)));
  expect(mesh.indices.length / 3).toBe(await trianglesShown(page));
  expect(mesh.comments[0]).toContain('at isovalue 0.43');
  // Vertices in voxel index space, inside the 128³ volume; the soup's shared corners welded.
  let lo = Infinity,
    hi = -Infinity;
  for (const v of mesh.positions) {
    lo = Math.min(lo, v);
    hi = Math.max(hi, v);
  }
  expect(lo).toBeGreaterThanOrEqual(0);
  expect(hi).toBeLessThanOrEqual(127);
  expect(mesh.positions.length / 3).toBeLessThan(mesh.indices.length / 2);
  for (const i of mesh.indices.subarray(0, 3000)) expect(i).toBeLessThan(mesh.positions.length / 3);
});

test('the URL keeps the isovalue and camera; the link reopens the same view', async ({ page, context }) => {
  await openApp(page);
  await setIsovalue(page, 0.37);
  const box = (await page.locator('#view').boundingBox())!;
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.down();
  await page.mouse.move(box.x + box.width / 2 + 100, box.y + box.height / 2 - 30, { steps: 5 });
  await page.mouse.up();
  await page.mouse.wheel(0, -300);
  const camera = await page.evaluate(() => window.zfpiso!.camera!());
  // The hash follows the view (throttled).
  const hash = `#${encodeViewState({ iso: 0.37, camera })}`;
  await page.waitForFunction((h) => location.hash === h, hash);
  const url = page.url();
  const triangles = await trianglesShown(page);

  await context.grantPermissions(['clipboard-read', 'clipboard-write']);
  await page.locator('#copy-link').click();
  await expect(page.locator('#messages .message.info').last()).toContainText('copied');
  expect(await page.evaluate(() => navigator.clipboard.readText())).toBe(url);

  const other = await context.newPage();
  await openApp(other, url.replace(/^https?:\/\/[^/]+/, ''));
  const s = await other.evaluate(() => ({ iso: window.zfpiso!.stats!.isovalue, camera: window.zfpiso!.camera!() }));
  expect(s.iso).toBe(Math.fround(0.37));
  expect(await trianglesShown(other)).toBe(triangles);
  for (let i = 0; i < 4; i++) expect(s.camera.rotation[i]).toBeCloseTo(camera.rotation[i], 5);
  expect(s.camera.distance).toBeCloseTo(camera.distance, 3);
  await expect(other.locator('#iso-value')).toHaveValue('0.3700');
});
