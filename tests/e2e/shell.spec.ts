import { expect, test } from '@playwright/test';
import { nonBackgroundFraction, openApp, waitForFrames, watchErrors } from './page.ts';

test('the page gets a WebGPU adapter and draws a frame', async ({ page }) => {
  const errors = watchErrors(page);
  await openApp(page);
  const adapter = await page.evaluate(() => window.zfpiso?.adapter);
  expect(adapter?.architecture).toBeTruthy();
  await expect(page.locator('#gpu-info dd[data-key="adapter"]')).toContainText(/swiftshader|/i);
  await waitForFrames(page, 1);
  expect(await nonBackgroundFraction(page)).toBeGreaterThan(0.001);
  expect(errors).toEqual([]);
});

test('a page without WebGPU explains what to do', async ({ page }) => {
  await page.addInitScript(() => {
    Object.defineProperty(navigator, 'gpu', { value: undefined });
  });
  await page.goto('/');
  await expect(page.locator('#fatal')).toContainText('needs WebGPU');
  await expect(page.locator('body')).toHaveAttribute('data-status', 'error');
});
