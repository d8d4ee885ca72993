// Scrubbing the isovalue: continuous input, the newest value wins (stale ones
// are dropped, not queued), keyboard steps on the slider and anywhere, the
// profile under the slider picks values; the GPU memory budget refuses growth
// with a readable message and keeps the surface.
import { expect, test } from '@playwright/test';
import { openApp } from './page.ts';
import { setIsovalue, trianglesShown } from './volume-page.ts';

test('scrubbing shows the newest value; stale values are dropped', async ({ page }) => {
  await openApp(page);
  const slider = page.locator('#iso-slider');
  const box = (await slider.boundingBox())!;
  const before = await page.evaluate(() => window.zfpiso!.statsCount);
  // Drag the slider thumb across: many input events, faster than surfaces come.
  await page.mouse.move(box.x + box.width * 0.5, box.y + box.height / 2);
  await page.mouse.down();
  const steps = 40;
  for (let i = 1; i <= steps; i++) await page.mouse.move(box.x + box.width * (0.5 - (0.2 * i) / steps), box.y + box.height / 2);
  await page.mouse.up();
  const last = await page.evaluate(() => window.zfpiso!.iso!);
  expect(last).toBeLessThan(0.4);
  // The surface ends at the last value, and fewer surfaces than inputs were computed.
  await page.waitForFunction(() => Math.fround(window.zfpiso!.stats!.isovalue) === Math.fround(window.zfpiso!.iso!), null, {
    timeout: 60_000,
  });
  const computed = (await page.evaluate(() => window.zfpiso!.statsCount)) - before;
  expect(computed).toBeGreaterThan(0);
  expect(computed).toBeLessThan(steps);
  await expect(page.locator('#iso-value')).toHaveValue(last.toFixed(4));
  // The URL follows.
  await page.waitForFunction((v) => location.hash.includes(`iso=${Number(v.toPrecision(7))}`), last);
});

test('keyboard steps, the profile, and the number field', async ({ page }) => {
  await openApp(page);
  const range = await page.evaluate(() => window.zfpiso!.volume!.valueRange);
  const step = (range[1] - range[0]) / 200;
  const at = async () => page.evaluate(() => window.zfpiso!.iso!);
  const start = await at();

  await page.locator('#iso-slider').focus();
  await page.keyboard.press('ArrowRight');
  expect(await at()).toBeCloseTo(start + step, 6);
  await page.keyboard.press('Shift+ArrowLeft');
  expect(await at()).toBeCloseTo(start - 9 * step, 6);
  await page.keyboard.press('PageUp');
  expect(await at()).toBeCloseTo(start + step, 6);

  // ] and [ work wherever the focus is (outside text fields).
  await page.locator('#view').focus();
  await page.keyboard.press(']');
  expect(await at()).toBeCloseTo(start + 2 * step, 6);
  await page.keyboard.press('Shift+BracketLeft');
  expect(await at()).toBeCloseTo(start - 8 * step, 6);

  // A click on the profile picks the value under the pointer.
  const profile = page.locator('#iso-profile');
  const pb = (await profile.boundingBox())!;
  await page.mouse.click(pb.x + pb.width * 0.25, pb.y + pb.height / 2);
  expect(await at()).toBeCloseTo(range[0] + 0.25 * (range[1] - range[0]), 2);
  await expect(page.locator('#profile-readout')).toContainText('blocks');

  // Typed values; out-of-range values are clamped when the field is left.
  await setIsovalue(page, 0.55);
  await page.locator('#iso-value').fill('7');
  await page.locator('#iso-value').press('Tab');
  expect(await at()).toBeCloseTo(range[1], 6);
});

test('a memory budget too small for a surface refuses it with a message and keeps the current one', async ({ page }) => {
  await openApp(page);
  const shown = await trianglesShown(page);
  const used = await page.evaluate(() => window.zfpiso!.stats!.cacheBytes + window.zfpiso!.stats!.vertexBytes);
  // Exactly what the current surface uses: bigger surfaces cannot grow into it.
  const mb = Math.max(1, Math.floor(used / 2 ** 20));
  await page.locator('#budget-mb').fill(String(mb));
  await page.locator('#budget-mb').press('Enter');
  // At 0.2 the built-in volume has more active blocks and triangles than at 0.5.
  await page.locator('#iso-value').fill('0.2');
  await page.locator('#iso-value').press('Enter');
  await expect(page.locator('#messages .message').last()).toContainText(/needs .* the budget is/);
  await expect(page.locator('#budget-note')).toContainText('raise the budget');
  expect(await trianglesShown(page)).toBe(shown);
  // Raising it lets the surface through.
  await page.locator('#budget-mb').fill('400');
  await page.locator('#budget-mb').press('Enter');
  await setIsovalue(page, 0.21);
  expect(await trianglesShown(page)).not.toBe(shown);
  await expect(page.locator('#budget-note')).toHaveText('');
});
