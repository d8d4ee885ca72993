// Helpers for the main page's tests: open volumes the ways users do (drop,
// picker, ?url=), answer the volume form, move the isovalue, and read what
// the panel shows. The shared data is served at /data/ by the dev/preview
// server (scripts/vite-shared-data.ts).
import { expect, type Page } from '@playwright/test';

export const SHARED_VOLUMES = '/data/volumes/';

/** Drops a file on the view the way a browser does: a DataTransfer with the file, from bytes fetched in the page. */
export async function dropFromUrl(page: Page, url: string, fileName = url.split('/').pop()!): Promise<void> {
  await page.evaluate(
    async ({ url, fileName }) => {
      const blob = await (await fetch(url)).blob();
      const file = new File([blob], fileName);
      const dt = new DataTransfer();
      dt.items.add(file);
      const target = document.getElementById('view')!;
      target.dispatchEvent(new DragEvent('dragenter', { dataTransfer: dt, bubbles: true, cancelable: true }));
      target.dispatchEvent(new DragEvent('dragover', { dataTransfer: dt, bubbles: true, cancelable: true }));
      target.dispatchEvent(new DragEvent('drop', { dataTransfer: dt, bubbles: true, cancelable: true }));
    },
    { url, fileName },
  );
}

/** Drops bytes made in the test (malformed files). */
export async function dropBytes(page: Page, fileName: string, bytes: Uint8Array): Promise<void> {
  await page.evaluate(
    ({ fileName, data }) => {
      const file = new File([new Uint8Array(data)], fileName);
      const dt = new DataTransfer();
      dt.items.add(file);
      document.getElementById('view')!.dispatchEvent(new DragEvent('drop', { dataTransfer: dt, bubbles: true, cancelable: true }));
    },
    { fileName, data: [...bytes] },
  );
}

export const loads = (page: Page) => page.evaluate(() => window.zfpiso!.loads);

/** Waits until the page has loaded one more volume than `before` and is idle. */
export async function waitForLoad(page: Page, before: number, timeout = 120_000): Promise<void> {
  await page.waitForFunction((n) => window.zfpiso!.loads > n && !window.zfpiso!.loading, before, { timeout });
}

/** Waits until a load attempt is over (success, failure or cancel). */
export async function waitIdle(page: Page, timeout = 120_000): Promise<void> {
  await page.waitForFunction(() => !window.zfpiso!.loading, null, { timeout });
}

/** The form that asks for a raw volume's rate (or missing shape): accept what it proposes. */
export async function acceptVolumeForm(page: Page): Promise<void> {
  const form = page.locator('#volume-form');
  await expect(form).toBeVisible({ timeout: 60_000 });
  await expect(form.locator('.form-ok')).toBeEnabled();
  await form.locator('.form-ok').click();
}

/** Sets the isovalue with the number field (as typed) and waits for its surface. */
export async function setIsovalue(page: Page, iso: number, timeout = 120_000): Promise<void> {
  await page.locator('#iso-value').fill(String(iso));
  await page.locator('#iso-value').press('Enter');
  await page.waitForFunction((v) => Math.fround(window.zfpiso!.stats?.isovalue ?? NaN) === Math.fround(v), iso, { timeout });
}

/** The triangle count the stats panel shows. */
export async function trianglesShown(page: Page): Promise<number> {
  const text = await page.locator('#surface-stats dd[data-key="triangles"]').textContent();
  return Number((text ?? '').replace(/[^\d]/g, ''));
}

export const pageState = (page: Page) =>
  page.evaluate(() => {
    const s = window.zfpiso!;
    return { volume: s.volume, iso: s.iso, stats: s.stats, loads: s.loads, messages: s.messages, loading: s.loading };
  });
