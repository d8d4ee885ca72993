// A store served by the preview server (/stores/, scripts/vite-stores.ts):
// `?store=` shows the coarsest level first, every finer level replaces it
// until level 0, fetching only the chunks the surface needs; the panel's
// figures agree with the CLI's records on the same store (chunks and chunk
// bytes fetched at level 0, triangles at the same isovalue); scrubbing goes
// through the stream; an unknown store is a message naming it while the
// page stays usable.
import { expect, test } from '@playwright/test';
import { convertNeghipStore, runCli } from './cli.ts';
import { openApp, watchErrors } from './page.ts';
import { trianglesShown } from './volume-page.ts';

let store = '';

interface StoreState {
  done: boolean;
  shownLevel: number;
  shownLevels: number[];
  chunkBytesFetched: number;
  bytesFetched: number;
  chunksFetched: number;
  reason: string | null;
  levels: { storedBytes: number; chunks: number; chunkBytes: number; chunksFetched: number; chunkBytesFetched: number }[];
  gpu: { total: number; budget: number };
  clippedChunks?: number;
}
const storeState = (page: import('@playwright/test').Page) =>
  page.evaluate(() => (window as unknown as { zfpisoStore: unknown }).zfpisoStore) as Promise<StoreState>;

test.beforeAll(() => {
  store = convertNeghipStore('neghip-e2e.zarr');
});

test('?store= shows coarse to fine; panel figures equal the CLI records', async ({ page }) => {
  test.setTimeout(300_000);
  const errors = watchErrors(page);
  await openApp(page, '/?store=/stores/neghip-e2e.zarr#iso=80');
  await page.waitForFunction(() => (window as unknown as { zfpisoStore?: { done: boolean } }).zfpisoStore?.done === true, null, {
    timeout: 240_000,
  });
  const st = await storeState(page);
  expect(st.reason).toBeNull();
  expect(st.shownLevels).toEqual([3, 2, 1, 0]);
  // only what the surface needs: at most every chunk of every level, each once; within the budget
  expect(st.chunkBytesFetched).toBe(st.levels.reduce((a, l) => a + l.chunksFetched * l.chunkBytes, 0));
  expect(st.levels[0].chunksFetched).toBeGreaterThan(0);
  expect(st.levels[0].chunksFetched).toBeLessThan(st.levels[0].chunks);
  expect(st.gpu.total).toBeLessThanOrEqual(st.gpu.budget);
  await expect(page.locator('#store-section table.store-levels tbody tr')).toHaveCount(4);
  await expect(page.locator('#store-section dd[data-k="chunks"]')).toHaveText(String(st.chunksFetched));
  await expect(page.locator('#store-section dd[data-k="bytes"]')).toHaveText(`${(st.bytesFetched / 2 ** 20).toFixed(2)} MiB`);
  await expect(page.locator('#store-progress')).toContainText('level 0 (full resolution)');
  const cli = await runCli<{ store: { chunkBytesFetched: number; chunks: number }; isosurfaces: { triangles: number }[] }>([
    'extract',
    store,
    '--level',
    '0',
    '--iso',
    '80',
  ]);
  expect(cli.store.chunks).toBe(st.levels[0].chunksFetched);
  expect(cli.store.chunkBytesFetched).toBe(st.levels[0].chunkBytesFetched);
  expect(await trianglesShown(page)).toBe(cli.isosurfaces[0].triangles);

  // scrubbing streams: a new isovalue ends at level 0 with the CLI's triangles there
  await page.locator('#iso-value').fill('40');
  await page.locator('#iso-value').press('Enter');
  await page.waitForFunction(
    () => {
      const s = (window as unknown as { zfpisoStore?: { done: boolean; shownLevel: number } }).zfpisoStore;
      const p = (window as unknown as { zfpiso?: { stats?: { isovalue: number } } }).zfpiso;
      return s?.done === true && s.shownLevel === 0 && p?.stats?.isovalue === 40;
    },
    null,
    { timeout: 240_000 },
  );
  const cli40 = await runCli<{ isosurfaces: { triangles: number }[] }>(['extract', store, '--level', '0', '--iso', '40']);
  expect(await trianglesShown(page)).toBe(cli40.isosurfaces[0].triangles);
  expect(errors).toEqual([]);
});

test('an unknown store is a message naming it; the page stays usable', async ({ page }) => {
  await openApp(page, '/?store=/stores/none.zarr');
  await expect(page.locator('#messages')).toContainText('/stores/none.zarr: no zarr.json, .zgroup or .zarray at its root');
});

test('a picked .zarr folder opens like the served store', async ({ page }) => {
  test.setTimeout(300_000);
  const errors = watchErrors(page);
  await openApp(page, '/#iso=80');
  await page.locator('input[webkitdirectory]').setInputFiles(store);
  await page.waitForFunction(() => (window as unknown as { zfpisoStore?: { done: boolean } }).zfpisoStore?.done === true, null, {
    timeout: 240_000,
  });
  const st = (await storeState(page)) as StoreState & { url: string };
  expect(st.url).toBe('neghip-e2e.zarr');
  expect(st.shownLevels).toEqual([3, 2, 1, 0]);
  expect(st.chunkBytesFetched).toBe(st.levels.reduce((a, l) => a + l.chunksFetched * l.chunkBytes, 0));
  await expect(page.locator('#store-progress')).toContainText('neghip-e2e.zarr: level 0 (full resolution)');
  expect(errors).toEqual([]);
});

test('the link keeps the level: #level=1 stops at level 1, and the hash says level=1', async ({ page }) => {
  test.setTimeout(300_000);
  await openApp(page, '/?store=/stores/neghip-e2e.zarr#iso=80&level=1');
  await page.waitForFunction(() => (window as unknown as { zfpisoStore?: { done: boolean } }).zfpisoStore?.done === true, null, {
    timeout: 240_000,
  });
  const st = await storeState(page);
  expect(st.levels[0].chunksFetched).toBe(0);
  expect(st.shownLevels).toEqual([3, 2, 1]);
  expect(st.reason).toBe('the link asks for level 1');
  await page.waitForFunction(() => /(^|&|#)level=1(&|$)/.test(location.hash) && /iso=80/.test(location.hash), null, { timeout: 10_000 });
  expect(new URL(page.url()).searchParams.get('store')).toBe('/stores/neghip-e2e.zarr');
});

test('a clip on a store: the chunks it removes whole are not fetched, as the CLI leaves them out', async ({ page }) => {
  test.setTimeout(300_000);
  await openApp(page, '/?store=/stores/neghip-e2e.zarr#iso=80&clip=0,0,0,30,65,65');
  await page.waitForFunction(() => (window as unknown as { zfpisoStore?: { done: boolean } }).zfpisoStore?.done === true, null, {
    timeout: 240_000,
  });
  const st = await storeState(page);
  expect(st.shownLevels).toEqual([3, 2, 1, 0]);
  expect(st.clippedChunks).toBeGreaterThan(0);
  const cli = await runCli<{ store: { chunks: number; clippedChunks: number } }>([
    'extract',
    store,
    '--level',
    '0',
    '--iso',
    '80',
    '--clip',
    '0,0,0,30,65,65',
  ]);
  expect(cli.store.clippedChunks).toBeGreaterThan(0);
  expect(st.levels[0].chunksFetched).toBe(cli.store.chunks);
});

test('two surfaces of a store: each step draws both from the same chunks (the CLI union), each with its own triangles', async ({
  page,
}) => {
  test.setTimeout(300_000);
  const errors = watchErrors(page);
  await openApp(page, '/?store=/stores/neghip-e2e.zarr#iso=80,40&level=0');
  const both = () =>
    page.waitForFunction(
      () => {
        const s = (window as unknown as { zfpisoStore?: { done: boolean; shownLevel: number } }).zfpisoStore;
        const e = window.zfpiso?.surfaces?.entries ?? [];
        return s?.done === true && s.shownLevel === 0 && e.length === 2 && e.every((x) => x.triangles !== undefined);
      },
      null,
      { timeout: 240_000 },
    );
  await both();
  const cli = await runCli<{ drawnTogether: number[]; store: { chunks: number }; isosurfaces: { iso: number; triangles: number }[] }>([
    'extract',
    store,
    '--level',
    '0',
    '--iso',
    '80,40',
  ]);
  expect(cli.drawnTogether).toEqual([80, 40]);
  const s = isoTriangles(await page.evaluate(() => window.zfpiso!.surfaces!));
  expect(s).toEqual(cli.isosurfaces.map((r) => [r.iso, r.triangles]));
  // level 0: the chunks either surface needs, each fetched once (the CLI's count, held to NumPy by the unit tests)
  expect((await storeState(page)).levels[0].chunksFetched).toBe(cli.store.chunks);

  // the second surface moved: the first keeps its triangles; the link holds both
  await page.locator('#surface-list li').nth(1).locator('input[type=radio]').check();
  await page.waitForFunction(() => window.zfpiso!.surfaces!.selected === 1);
  await page.locator('#iso-value').fill('120');
  await page.locator('#iso-value').press('Enter');
  await page.waitForFunction(
    () => {
      const e = window.zfpiso?.surfaces?.entries ?? [];
      const st = (window as unknown as { zfpisoStore?: { done: boolean } }).zfpisoStore;
      return st?.done === true && e[1]?.iso === 120 && e[1].triangles !== undefined && e[0].triangles !== undefined;
    },
    null,
    { timeout: 240_000 },
  );
  const cli120 = await runCli<{ isosurfaces: { triangles: number }[] }>(['extract', store, '--level', '0', '--iso', '120']);
  expect(isoTriangles(await page.evaluate(() => window.zfpiso!.surfaces!))).toEqual([
    [80, cli.isosurfaces[0].triangles],
    [120, cli120.isosurfaces[0].triangles],
  ]);
  await page.waitForFunction(() => location.hash.includes('iso=80,120'));
  // hidden: the stream no longer draws it (its triangles are gone from the step)
  await page.locator('#surface-list li').nth(0).locator('input[type=checkbox]').uncheck();
  await page.waitForFunction(() => window.zfpiso?.surfaces?.entries[0].triangles === undefined, null, { timeout: 120_000 });
  expect(errors).toEqual([]);
});

/** [iso, triangles] per surface. */
function isoTriangles(s: { entries: { iso: number; triangles?: number }[] }): [number, number | undefined][] {
  return s.entries.map((e) => [e.iso, e.triangles]);
}

test('another volume replaces the store: its GPU side goes, no WebGPU error, and the store stops publishing', async ({ page }) => {
  test.setTimeout(300_000);
  const errors = watchErrors(page);
  await openApp(page, '/?store=/stores/neghip-e2e.zarr#iso=80&level=2');
  await page.waitForFunction(() => (window as unknown as { zfpisoStore?: { done: boolean } }).zfpisoStore?.done === true, null, {
    timeout: 240_000,
  });
  await page.locator('#load-default').click();
  await page.waitForFunction(
    () => (window as unknown as { zfpiso: { volume?: { kind: string } } }).zfpiso.volume?.kind === 'default',
    null,
    { timeout: 120_000 },
  );
  // frames keep being drawn from the new volume's buffers (a freed store buffer would be a validation error)
  const frames = () => page.evaluate(() => (window as unknown as { zfpiso: { framesDrawn(): number } }).zfpiso.framesDrawn());
  const before = await frames();
  await page.keyboard.press(']');
  await page.waitForFunction((n) => (window as unknown as { zfpiso: { framesDrawn(): number } }).zfpiso.framesDrawn() > n, before, {
    timeout: 60_000,
  });
  await page.waitForTimeout(500);
  await expect(page.locator('#messages')).not.toContainText(/WebGPU|validation|destroyed/i);
  await expect(page.locator('#store-progress')).toBeHidden();
  await expect(page.locator('#store-section')).toBeHidden();
  expect(errors).toEqual([]);
});
