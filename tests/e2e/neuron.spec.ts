// The neuron page: the shared TIFF stack (libtiff Wasm module) ray-marched,
// with its isosurface (compressed on the GPU, the main page's pipeline and
// surface layer) where the volume's structure is, and the shared SWC trace
// in the same view; a bad file; the demo cell.
import { fileURLToPath } from 'node:url';
import { expect, test, type Page } from '@playwright/test';
import { nonBackgroundFraction, openApp, waitForFrames, watchErrors } from './page.ts';

const data = (p: string) => fileURLToPath(new URL(`../../../shared/data/${p}`, import.meta.url));

type PixelKind = 'trace-red' | 'volume-green' | 'volume-lit' | 'surface-orange';

/**
 * Per kind, the pixels of the view (a screenshot) of that colour. Basal
 * dendrites are drawn red (SWC type 3), the fluorescence map is green (and
 * white-green where the volume is brightest: 'volume-lit' takes both), the
 * isosurface is orange (#e6a15c, lit: green 45-85% of red and well above
 * blue, which tells it from the red traces' white highlights).
 * With `within`, a second screenshot: how many `within.kind` pixels it has
 * (`inOther`), and how many of them are on the first one's `within.of`
 * pixels (`overlap`: the same place on screen).
 */
async function pixels(
  page: Page,
  within?: { png: Buffer; kind: PixelKind; of: PixelKind },
): Promise<Record<PixelKind, number> & { inOther: number; overlap: number }> {
  const png = await page.locator('#view').screenshot();
  return page.evaluate(
    async ({ shots, within }) => {
      const read = async (bytes: number[]) => {
        const bitmap = await createImageBitmap(new Blob([new Uint8Array(bytes)], { type: 'image/png' }));
        const c = new OffscreenCanvas(bitmap.width, bitmap.height);
        const g = c.getContext('2d')!;
        g.drawImage(bitmap, 0, 0);
        return g.getImageData(0, 0, bitmap.width, bitmap.height).data;
      };
      const is = (kind: string, r: number, g: number, b: number) =>
        kind === 'trace-red'
          ? r > 150 && g < 110 && b < 110
          : kind === 'volume-green'
            ? g > 90 && g > r + 25 && g > b + 25
            : kind === 'volume-lit'
              ? g > 60 && g >= r && g >= b
              : r > 90 && g > 0.45 * r && g < 0.85 * r && g - b > 0.12 * r;
      const [a, b] = await Promise.all(shots.map(read));
      const out = { 'trace-red': 0, 'volume-green': 0, 'volume-lit': 0, 'surface-orange': 0, inOther: 0, overlap: 0 };
      for (let i = 0; i < a.length; i += 4) {
        for (const k of ['trace-red', 'volume-green', 'volume-lit', 'surface-orange'] as const)
          if (is(k, a[i], a[i + 1], a[i + 2])) out[k]++;
        if (within && b && is(within.kind, b[i], b[i + 1], b[i + 2])) {
          out.inOther++;
          if (is(within.of, a[i], a[i + 1], a[i + 2])) out.overlap++;
        }
      }
      return out;
    },
    { shots: [[...png], ...(within ? [[...within.png]] : [])], within: within && { kind: within.kind, of: within.of } },
  );
}

const countPixels = async (page: Page, kind: PixelKind) => (await pixels(page))[kind];

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

  // The isosurface: compressed at the default rate 8, Otsu's isovalue between background (0) and structure (255).
  expect(s.surface).toMatchObject({ computing: false, visible: true, rate: 8 });
  expect(s.surface!.isovalue).toBeGreaterThan(50);
  expect(s.surface!.isovalue).toBeLessThan(205);
  const triangles = Number((await page.locator('#surface-stats dd[data-key="triangles"]').textContent())!.replace(/,/g, ''));
  expect(triangles).toBeGreaterThan(10_000);
  expect(triangles).toBe(s.surface!.triangles);
  await expect(page.locator('#surface-stats dd[data-key="zfp stream"]')).toContainText('at 8 bits/value');
  await expect(page.locator('#iso-value')).toBeEnabled();
  await waitForFrames(page, 2);
  await redraw(page);
  expect(await nonBackgroundFraction(page)).toBeGreaterThan(0.03);
  // Opaque: the ray marcher stops at it, so the structure shows the surface's colour, not the volume's.
  const withSurface = await pixels(page);
  expect(withSurface['surface-orange']).toBeGreaterThan(5000);
  expect(withSurface['volume-green']).toBeLessThan(withSurface['surface-orange'] / 10);
  expect(withSurface['trace-red']).toBeGreaterThan(30);

  // In the same place as the volume's bright structure: the surface alone vs the volume alone, same view.
  await page.locator('#show-volume').uncheck();
  await redraw(page);
  const surfaceOnly = await page.locator('#view').screenshot();
  await page.locator('#show-volume').check();
  await page.locator('#show-surface').uncheck();
  await redraw(page);
  const volumeOnly = await pixels(page, { png: surfaceOnly, kind: 'surface-orange', of: 'volume-lit' });
  // Hidden: its pixels are gone (a few remain orange where the red trace shows through the green volume).
  expect(volumeOnly['surface-orange']).toBeLessThan(withSurface['surface-orange'] / 100);
  expect(volumeOnly['volume-green']).toBeGreaterThan(2000);
  // Nearly every surface pixel lies on the structure, and covers most of it (a flipped axis would not).
  expect(volumeOnly.inOther).toBeGreaterThan(5000);
  expect(volumeOnly.overlap).toBeGreaterThan(0.9 * volumeOnly.inOther);
  expect(volumeOnly.overlap).toBeGreaterThan(0.8 * volumeOnly['volume-lit']);
  expect(volumeOnly['trace-red']).toBeGreaterThan(30);

  // The trace alone (volume and surface hidden) and as lines.
  await page.locator('#show-volume').uncheck();
  await page.getByText('Lines', { exact: true }).click();
  await redraw(page);
  const traceOnly = await pixels(page);
  expect(traceOnly['volume-green']).toBe(0);
  expect(traceOnly['surface-orange']).toBe(0);
  expect(traceOnly['trace-red']).toBeGreaterThan(10);

  // Another isovalue (number field) and another rate: new surfaces, the panel follows.
  await page.locator('#show-surface').check();
  await page.locator('#iso-value').fill('230');
  await page.waitForFunction(() => window.neuron!.surface!.drawnIsovalue === 230);
  await page.locator('#surface-rate').selectOption('4');
  await page.waitForFunction(() => window.neuron!.surface!.rate === 4 && !window.neuron!.surface!.computing);
  await expect(page.locator('#surface-stats dd[data-key="zfp stream"]')).toContainText('at 4 bits/value');
  // The isovalue is kept across the rate change.
  expect(await page.evaluate(() => window.neuron!.surface!.drawnIsovalue)).toBe(230);
  await expect(page.locator('#iso-value')).toHaveValue(/^230(\.0+)?$/);
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
  // Its isosurface follows the volume (computed after the page is ready).
  await page.waitForFunction(() => (window.neuron!.surface!.triangles ?? 0) > 0 && !window.neuron!.surface!.computing, null, {
    timeout: 60_000,
  });
  await waitForFrames(page, 1);
  await redraw(page);
  expect(await countPixels(page, 'surface-orange')).toBeGreaterThan(1000);
  await page.locator('#show-surface').uncheck();
  await redraw(page);
  expect(await countPixels(page, 'volume-green')).toBeGreaterThan(1000);
});
