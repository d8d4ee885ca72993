// Helpers for page tests: open the app, wait until it is ready, and look at
// what a user would see.
import { expect, type Page } from '@playwright/test';

/** Collects console errors and page errors so tests can assert on them. */
export function watchErrors(page: Page): string[] {
  const errors: string[] = [];
  page.on('pageerror', (e) => errors.push(`pageerror: ${e.message}`));
  page.on('console', (m) => {
    if (m.type() === 'error') errors.push(`console: ${m.text()}`);
  });
  return errors;
}

export async function openApp(page: Page, path = '/'): Promise<void> {
  await page.goto(path);
  await expect(page.locator('body')).toHaveAttribute('data-status', /ready|error/, { timeout: 120_000 });
  const fatal = page.locator('#fatal');
  if (await fatal.count()) throw new Error(`page shows a fatal error: ${await fatal.textContent()}`);
}

/** Waits until the viewer has drawn at least `n` frames. */
export async function waitForFrames(page: Page, n = 1): Promise<void> {
  await page.waitForFunction((count) => (window.zfpiso?.framesDrawn() ?? 0) >= count, n, { timeout: 60_000 });
}

/** Fraction of canvas pixels that differ from the clear colour (from a screenshot). */
export async function nonBackgroundFraction(page: Page): Promise<number> {
  const png = await page.locator('#view').screenshot();
  return page.evaluate(
    async (bytes) => {
      const blob = new Blob([new Uint8Array(bytes)], { type: 'image/png' });
      const bitmap = await createImageBitmap(blob);
      const c = new OffscreenCanvas(bitmap.width, bitmap.height);
      const g = c.getContext('2d')!;
      g.drawImage(bitmap, 0, 0);
      const { data } = g.getImageData(0, 0, bitmap.width, bitmap.height);
      // The clear colour is the top-left pixel's (the view's corner is background).
      const [r0, g0, b0] = [data[0], data[1], data[2]];
      let differ = 0;
      for (let i = 0; i < data.length; i += 4) {
        if (Math.abs(data[i] - r0) + Math.abs(data[i + 1] - g0) + Math.abs(data[i + 2] - b0) > 12) differ++;
      }
      return differ / (data.length / 4);
    },
    [...png],
  );
}

/** Waits until the store's refinement has ended with level 0 on screen (window.zfpisoStore). */
export function level0Shown(page: Page, timeout = 240_000) {
  return page.waitForFunction(
    () => {
      const s = (window as unknown as { zfpisoStore?: { done: boolean; shownLevel: number } }).zfpisoStore;
      return s?.done === true && s.shownLevel === 0;
    },
    null,
    { timeout },
  );
}
