// The neuron page: the shared TIFF stack (libtiff Wasm module) ray-marched,
// with the shared SWC trace in the same view; a bad file; the demo cell.
import { fileURLToPath } from 'node:url';
import { expect, test, type Page } from '@playwright/test';
import { nonBackgroundFraction, openApp, waitForFrames, watchErrors } from './page.ts';

const data = (p: string) => fileURLToPath(new URL(`../../../shared/data/${p}`, import.meta.url));

/** Pixels of the view whose colour matches `test` (from a screenshot). */
async function countPixels(page: Page, kind: 'trace-red' | 'volume-green'): Promise<number> {
  const png = await page.locator('#view').screenshot();
  return page.evaluate(
    async ({ bytes, kind }) => {
      const bitmap = await createImageBitmap(new Blob([new Uint8Array(bytes)], { type: 'image/png' }));
      const c = new OffscreenCanvas(bitmap.width, bitmap.height);
      const g = c.getContext('2d')!;
      g.drawImage(bitmap, 0, 0);
      const { data } = g.getImageData(0, 0, bitmap.width, bitmap.height);
      let n = 0;
      for (let i = 0; i < data.length; i += 4) {
        const [r, gr, b] = [data[i], data[i + 1], data[i + 2]];
        // Basal dendrites are drawn red (SWC type 3); the fluorescence map is green.
        if (kind === 'trace-red' ? r > 150 && gr < 110 && b < 110 : gr > 90 && gr > r + 25 && gr > b + 25) n++;
      }
      return n;
    },
    { bytes: [...png], kind },
  );
}

const redraw = (page: Page) => page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));

test('the shared TIFF stack and SWC trace show together', async ({ page }) => {
  const errors = watchErrors(page);
  await openApp(page, '/neuron.html?demo=0');
  await expect(page.locator('#empty-hint')).toBeVisible();
  await page.setInputFiles('#file-input', [data('tiff/morpholibj_bat-cochlea-volume.tif'), data('swc/neurom_Neuron.swc')]);
  await page.waitForFunction(() => window.neuron?.volume !== undefined && !window.neuron.loading, null, { timeout: 120_000 });
  const s = await page.evaluate(() => window.neuron!);
  expect(s.volume!.dims).toEqual([121, 154, 114]);
  expect(s.volume!.dtype).toBe('uint8');
  expect(s.traces).toEqual([{ name: 'neurom_Neuron.swc', samples: 847, visible: true }]);
  await expect(page.locator('#volume-info dd[data-key="size"]')).toHaveText('121 × 154 × 114 voxels');
  await expect(page.locator('#trace-list')).toContainText('neurom_Neuron.swc');
  await expect(page.locator('#trace-legend')).toContainText('basal dendrite');
  await expect(page.locator('#empty-hint')).toBeHidden();
  await waitForFrames(page, 2);
  await redraw(page);
  expect(await nonBackgroundFraction(page)).toBeGreaterThan(0.03);
  expect(await countPixels(page, 'volume-green')).toBeGreaterThan(2000);
  expect(await countPixels(page, 'trace-red')).toBeGreaterThan(30);

  // The trace alone (volume hidden) and as lines.
  await page.locator('#show-volume').uncheck();
  await page.getByText('Lines', { exact: true }).click();
  await redraw(page);
  expect(await countPixels(page, 'volume-green')).toBe(0);
  expect(await countPixels(page, 'trace-red')).toBeGreaterThan(10);
  expect(errors).toEqual([]);
});

test('a broken TIFF gives a message naming it, and the page keeps working', async ({ page }) => {
  await openApp(page, '/neuron.html?demo=0');
  await page.setInputFiles('#file-input', { name: 'scan.tif', mimeType: 'image/tiff', buffer: Buffer.from('II*\u0000 not really a tiff') });
  await expect(page.locator('#messages .message')).toContainText('scan.tif: truncated or corrupt TIFF');
  await page.setInputFiles('#file-input', { name: 'bad.swc', mimeType: 'text/plain', buffer: Buffer.from('1 1 0 0\n') });
  await expect(page.locator('#messages .message')).toContainText('bad.swc, line 1: expected 7 columns');
  await expect(page.locator('body')).toHaveAttribute('data-status', 'ready');
});

test('the demo cell is shown on open', async ({ page }) => {
  await openApp(page, '/neuron.html');
  const s = await page.evaluate(() => window.neuron!);
  expect(s.demo).toBe(true);
  expect(s.traces[0].samples).toBeGreaterThan(100);
  await waitForFrames(page, 1);
  await redraw(page);
  expect(await countPixels(page, 'volume-green')).toBeGreaterThan(1000);
});
