// A zipped OME-Zarr store written by ngff-zarr (.ozx, RFC 9;
// tests/fixtures/ngff-stores.py) in the page: by URL (`?store=…ozx`, read
// in place with range requests) and picked as a file with "Open file…"
// (read in place with File.slice). Each shows level 0 with the CLI's
// triangles on the same file, and the levels ngff-zarr wrote.
import { execFileSync } from 'node:child_process';
import { mkdirSync } from 'node:fs';
import { join } from 'node:path';
import { expect, test } from '@playwright/test';
import { E2E_STORES_DIR, runCli, SHARED_VOLUMES_DIR } from './cli.ts';
import { level0Shown, nonBackgroundFraction, openApp, watchErrors } from './page.ts';
import { trianglesShown } from './volume-page.ts';

const root = join(import.meta.dirname, '..', '..');
const folder = join(E2E_STORES_DIR, 'ngff');
let ozx = '';

test.beforeAll(() => {
  mkdirSync(folder, { recursive: true });
  const out = execFileSync(
    join(root, '.venv-converter/bin/python'),
    [join(root, 'tests/fixtures/ngff-stores.py'), folder, SHARED_VOLUMES_DIR],
    {
      encoding: 'utf8',
      timeout: 300_000,
      stdio: ['ignore', 'pipe', 'ignore'],
    },
  );
  ozx = (JSON.parse(out) as Record<string, { store: string }>).neghip_ozx.store;
});

/** ngff-zarr leaves out chunks that are all fill value: their 404s are not errors. */
const realErrors = (logged: string[]) => logged.filter((e) => !/status of 404/.test(e));

test('?store= of an .ozx: read in place by range requests, level 0 = the CLI on the same file', async ({ page }) => {
  test.setTimeout(300_000);
  const logged = watchErrors(page);
  await openApp(page, '/?store=/stores/ngff/neghip.ozx#iso=80.5&rate=8');
  await level0Shown(page);
  const st = (await page.evaluate(() => (window as unknown as { zfpisoStore: unknown }).zfpisoStore)) as {
    levels: { dims: number[] }[];
    reason: string | null;
  };
  expect(st.reason).toBeNull();
  expect(st.levels.map((l) => l.dims)).toEqual([
    [66, 66, 66],
    [33, 33, 33],
  ]);
  await expect(page.locator('#store-section dd[data-k="format"]')).toHaveText('Zarr v3');
  const cli = await runCli<{ isosurfaces: { triangles: number }[] }>(['extract', ozx, '--level', '0', '--iso', '80.5', '--rate', '8']);
  expect(await trianglesShown(page)).toBe(cli.isosurfaces[0].triangles);
  expect(realErrors(logged)).toEqual([]);
});

test('an .ozx picked with "Open file…" opens as a store (not as a volume file), the same surface', async ({ page }) => {
  test.setTimeout(300_000);
  const logged = watchErrors(page);
  await openApp(page, '/#iso=80.5&rate=8');
  await page.locator('#file-input').setInputFiles(ozx);
  await level0Shown(page);
  await expect(page.locator('#store-section dd[data-k="format"]')).toHaveText('Zarr v3');
  const iso = await page.evaluate(() => (window as unknown as { zfpiso: { stats: { isovalue: number } } }).zfpiso.stats.isovalue);
  const rate = await page.locator('#store-section input[data-choice="storeRate"]').inputValue();
  const cli = await runCli<{ isosurfaces: { triangles: number }[] }>(['extract', ozx, '--level', '0', `--iso=${iso}`, '--rate', rate]);
  expect(await trianglesShown(page)).toBe(cli.isosurfaces[0].triangles);
  await expect(page.locator('#messages .message.error')).toHaveCount(0);
  expect(realErrors(logged)).toEqual([]);
});

test('a pyramid whose level 1 halves only z: level 1 drawn at its scale (1, 1, 2) where its translation puts it, level by level and in the cut', async ({
  page,
}) => {
  test.setTimeout(300_000);
  const logged = watchErrors(page);
  // level by level, pinned at level 1 by the link: its voxels are 1 x 1 x 2 of level 0's, half a voxel up z
  await openApp(page, '/?store=/stores/ngff/hydrogen_aniso.ome.zarr#iso=1500.5&rate=8&level=1');
  await page.waitForFunction(
    () => {
      const s = (window as unknown as { zfpisoStore?: { done: boolean; shownLevel: number } }).zfpisoStore;
      return s?.done === true && s.shownLevel === 1;
    },
    null,
    { timeout: 240_000 },
  );
  const st = (await page.evaluate(() => (window as unknown as { zfpisoStore: unknown }).zfpisoStore)) as {
    levels: { dims: number[] }[];
    parts: { level: number; scale: number[]; origin: number[] }[];
  };
  expect(st.levels.map((l) => l.dims)).toEqual([
    [128, 128, 128],
    [128, 128, 64],
    [64, 64, 64],
  ]);
  // the store is one volume on screen (level 0's frame); level 1's piece at its scale, where its translation puts it
  const volume = await page.evaluate(
    () => (window as unknown as { zfpiso: { volume: { dims: number[]; spacing: number[] } } }).zfpiso.volume,
  );
  expect(volume).toMatchObject({ dims: [128, 128, 128], spacing: [1, 1, 1] });
  expect(st.parts).toEqual([{ level: 1, scale: [1, 1, 2], origin: [0, 0, 0.25] }]);
  const store = join(folder, 'hydrogen_aniso.ome.zarr');
  const cli = await runCli<{ isosurfaces: { triangles: number }[] }>(['extract', store, '--level', '1', '--iso', '1500.5', '--rate', '8']);
  expect(await trianglesShown(page)).toBe(cli.isosurfaces[0].triangles);
  // refined by the view (a fresh load: the same URL with another hash would not reload): the whole cut shown, frames drawn, no error
  await page.goto('about:blank');
  await openApp(page, '/?store=/stores/ngff/hydrogen_aniso.ome.zarr#iso=1500.5&rate=8&cut=1');
  await page.waitForFunction(
    () => {
      const s = (window as unknown as { zfpisoStore?: { done: boolean; cut: { final: boolean } | null } }).zfpisoStore;
      return s?.done === true && s.cut?.final === true;
    },
    null,
    { timeout: 240_000 },
  );
  expect(await nonBackgroundFraction(page)).toBeGreaterThan(0.01);
  await expect(page.locator('#messages .message.error')).toHaveCount(0);
  expect(realErrors(logged)).toEqual([]);
});
