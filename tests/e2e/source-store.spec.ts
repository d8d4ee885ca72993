// A store of lossless chunks (Zarr v3 + zstd, uint8, an OME-Zarr pyramid of
// 3 levels written by zarr-python from neghip) served by the preview
// server: `?store=` shows its levels coarse to fine, each brick compressed
// on the GPU as it arrives; the panel names the codec and the type; level
// 0's triangles equal the CLI's on the same store (the rate chosen from the
// data by both); the link keeps the GPU rate; chunks are decoded in Web Workers, and long main-thread tasks while
// they stream are recorded.
import { execFileSync } from 'node:child_process';
import { mkdirSync, rmSync } from 'node:fs';
import { join } from 'node:path';
import { expect, test } from '@playwright/test';
import { E2E_STORES_DIR, runCli, SHARED_VOLUMES_DIR } from './cli.ts';
import { level0Shown, openApp, watchErrors } from './page.ts';
import { setIsovalue, trianglesShown } from './volume-page.ts';

const root = join(import.meta.dirname, '..', '..');
let store = '';

test.beforeAll(() => {
  store = join(E2E_STORES_DIR, 'neghip-zstd.zarr');
  rmSync(store, { recursive: true, force: true });
  mkdirSync(E2E_STORES_DIR, { recursive: true });
  execFileSync(
    join(root, '.venv-converter/bin/python'),
    [
      '-c',
      `
import sys, numpy as np, zarr
from zarr.codecs import ZstdCodec
a = np.fromfile(sys.argv[1], dtype=np.uint8).reshape(66, 66, 66)
g = zarr.open_group(sys.argv[2], mode='w', zarr_format=3)
levels = [a]
for _ in range(2):
    p = levels[-1]; s = [n // 2 * 2 for n in p.shape]
    levels.append(np.round(p[:s[0], :s[1], :s[2]].reshape(s[0] // 2, 2, s[1] // 2, 2, s[2] // 2, 2).mean(axis=(1, 3, 5))).astype(np.uint8))
for i, lv in enumerate(levels):
    g.create_array(str(i), shape=lv.shape, chunks=(16, 16, 16), dtype='uint8', compressors=ZstdCodec(level=3))[...] = lv
axes = [{'name': n, 'type': 'space', 'unit': 'micrometer'} for n in 'zyx']
g.attrs['ome'] = {'version': '0.5', 'multiscales': [{'axes': axes, 'datasets': [
    {'path': str(i), 'coordinateTransformations': [{'type': 'scale', 'scale': [2.0 ** i] * 3}]} for i in range(3)]}]}
`,
      join(SHARED_VOLUMES_DIR, 'neghip_66x66x66_uint8.raw'),
      store,
    ],
    { timeout: 300_000, stdio: 'ignore' },
  );
});

test('?store= of a zstd store: levels coarse to fine, codec and type named, level 0 = the CLI', async ({ page }) => {
  test.setTimeout(300_000);
  // zarr-python leaves out chunks that are all fill value: their 404s are the store's way of saying so, not errors
  const logged = watchErrors(page);
  const errors = {
    get list() {
      return logged.filter((e) => !/Failed to load resource: the server responded with a status of 404/.test(e));
    },
  };
  await page.addInitScript(() => {
    const w = window as unknown as { longTasks: number[] };
    w.longTasks = [];
    new PerformanceObserver((list) => {
      for (const e of list.getEntries()) w.longTasks.push(e.duration);
    }).observe({ type: 'longtask', buffered: true });
  });
  await openApp(page, '/?store=/stores/neghip-zstd.zarr#iso=80');
  const before = await page.evaluate(() => (window as unknown as { longTasks: number[] }).longTasks.length);
  await page.waitForFunction(() => (window as unknown as { zfpisoStore?: { done: boolean } }).zfpisoStore?.done === true, null, {
    timeout: 240_000,
  });
  const st = (await page.evaluate(() => (window as unknown as { zfpisoStore: unknown }).zfpisoStore)) as {
    shownLevels: number[];
    reason: string | null;
    gpu: { total: number; budget: number };
  };
  expect(st.reason).toBeNull();
  expect(st.shownLevels).toEqual([2, 1, 0]);
  expect(st.gpu.total).toBeLessThanOrEqual(st.gpu.budget);
  await expect(page.locator('#store-section dd[data-k="codec"]')).toHaveText('bytes + zstd');
  await expect(page.locator('#store-section dd[data-k="dtype"]')).toContainText('uint8');
  await expect(page.locator('#store-section dd[data-k="format"]')).toHaveText('Zarr v3');
  await expect(page.locator('#store-progress')).toContainText('level 0 (full resolution)');
  // information about the store goes to the panel, not to notices over the view (issue 37)
  await expect(page.locator('#store-section dd[data-k="notes"]')).toContainText(/chunks are decoded in \d Web Workers?/);
  // no rate asked for: chosen from the data (issue 30's rule), as the CLI chooses it
  await expect(page.locator('#store-section dd[data-k="notes"]')).toContainText(/rate \d+ chosen from the data/);
  await expect(page.locator('#messages .message.error')).toHaveCount(0);
  const cli = await runCli<{ rate: number; isosurfaces: { triangles: number }[] }>(['extract', store, '--level', '0', '--iso', '80']);
  await expect(page.locator('#store-section input[data-choice="storeRate"]')).toHaveValue(String(cli.rate));
  expect(await trianglesShown(page)).toBe(cli.isosurfaces[0].triangles);
  await expect.poll(() => new URL(page.url()).hash).toContain(`rate=${cli.rate}`);
  const longTasks = await page.evaluate((n) => (window as unknown as { longTasks: number[] }).longTasks.slice(n), before);
  console.log(`long main-thread tasks while the store streamed: ${longTasks.length}, longest ${Math.max(0, ...longTasks).toFixed(0)} ms`);
  expect(errors.list).toEqual([]);

  // another GPU rate from the panel: the store opens again at that rate, and the link says so
  expect(cli.rate).not.toBe(4);
  await page.locator('#store-section input[data-choice="storeRate"]').fill('4');
  await page.locator('#store-section input[data-choice="storeRate"]').dispatchEvent('change');
  await expect.poll(() => new URL(page.url()).hash, { timeout: 120_000 }).toContain('rate=4');
  await level0Shown(page);
  const cli4 = await runCli<{ isosurfaces: { triangles: number }[] }>(['extract', store, '--level', '0', '--iso', '80', '--rate', '4']);
  expect(await trianglesShown(page)).toBe(cli4.isosurfaces[0].triangles);
  expect(errors.list).toEqual([]);
});

test('a picked folder of lossless chunks opens the same way, decoded in workers from the picked files', async ({ page }) => {
  test.setTimeout(300_000);
  const logged = watchErrors(page);
  await openApp(page, '/');
  await page.locator('input[webkitdirectory]').setInputFiles(store);
  await level0Shown(page);
  await expect(page.locator('#store-section dd[data-k="notes"]')).toContainText(/chunks are decoded in \d Web Workers?/);
  await expect(page.locator('#store-section dd[data-k="codec"]')).toHaveText('bytes + zstd');
  // the isovalue the page chose for the store (the link's went to the built-in volume shown first)
  const iso = await page.evaluate(() => (window as unknown as { zfpiso: { stats: { isovalue: number } } }).zfpiso.stats.isovalue);
  const cli = await runCli<{ isosurfaces: { triangles: number }[] }>(['extract', store, '--level', '0', `--iso=${iso}`]);
  expect(await trianglesShown(page)).toBe(cli.isosurfaces[0].triangles);
  expect(logged).toEqual([]);
});

/** [min, max] over level 0's bricks at `rate` as zfpy decodes them (convert --ranges-only). */
function sidecarRange(rate: string): [number, number] {
  const out = join(E2E_STORES_DIR, `neghip-zstd-ranges-${rate}.zarr`);
  execFileSync(process.execPath, [join(root, 'scripts/convert.mjs'), store, '--out', out, '--ranges-only', '--rate', rate, '--quiet'], {
    timeout: 300_000,
    stdio: 'ignore',
  });
  const printed = execFileSync(
    join(root, '.venv-converter/bin/python'),
    [
      '-c',
      "import sys, zarr; r = zarr.open_array(sys.argv[1] + '/ranges/0')[...]; print(float(r[..., 0].min()), float(r[..., 1].max()))",
      out,
    ],
    { encoding: 'utf8' },
  );
  return printed.trim().split(' ').map(Number) as [number, number];
}

for (const cut of [false, true])
  test(`a store with no value range in its metadata${cut ? ', refined by the view' : ''}: the coarsest level read at open gives the slider's range (provisional), widened to level 0's as its bricks are read; the link's isovalue is kept as given`, async ({
    page,
  }) => {
    test.setTimeout(300_000);
    const logged = watchErrors(page);
    // above every value (uint8): the link's isovalue must not be clamped or replaced (the surface is empty)
    await openApp(page, `/?store=/stores/neghip-zstd.zarr#iso=300${cut ? '&cut=1' : ''}`);
    const range = page.locator('#store-section dd[data-k="value-range"]');
    // provisional at first (the coarsest level's, read at open; too brief here to catch reliably), final once
    // every brick of level 0 is known
    await level0Shown(page);
    await expect(range).not.toContainText('provisional', { timeout: 60_000 });
    await expect(range).toHaveAttribute('title', /every brick of level 0/);
    const [lo, hi] = ((await range.textContent()) ?? '').split(' (')[0].split(' .. ').map(Number);
    const rate = await page.locator('#store-section input[data-choice="storeRate"]').inputValue();
    const [tlo, thi] = sidecarRange(rate);
    expect(lo).toBeCloseTo(tlo, 3);
    expect(hi).toBeCloseTo(thi, 3);
    // the slider's ends say so too
    const max = Number((await page.locator('#iso-max').textContent())?.replace(/[^0-9.eE+-]/g, ''));
    expect(Math.abs(max - thi)).toBeLessThan(0.01 * (thi - tlo));
    const iso = await page.evaluate(() => (window as unknown as { zfpiso: { stats: { isovalue: number } } }).zfpiso.stats.isovalue);
    expect(iso).toBe(300);
    await expect(page.locator('#iso-value')).toHaveValue(/^300/);
    expect(logged.filter((e) => !/status of 404/.test(e))).toEqual([]);
  });

/** Bricks of level 0 a surface at `iso` reads by zfpy's ranges at `rate` (convert --ranges-only): lo < iso <= hi over each brick's 27 neighbours. */
function neededByRanges(rate: string, iso: number): number {
  const out = join(E2E_STORES_DIR, `neghip-zstd-ranges-${rate}.zarr`);
  const printed = execFileSync(
    join(root, '.venv-converter/bin/python'),
    [
      '-c',
      `
import sys, numpy as np, zarr
r = zarr.open_array(sys.argv[1] + '/ranges/0')[...].astype(np.float64)
lo = np.pad(r[..., 0], 1, constant_values=np.inf)
hi = np.pad(r[..., 1], 1, constant_values=-np.inf)
z, y, x = r.shape[:3]
nlo = np.min([lo[a:a + z, b:b + y, c:c + x] for a in range(3) for b in range(3) for c in range(3)], axis=0)
nhi = np.max([hi[a:a + z, b:b + y, c:c + x] for a in range(3) for b in range(3) for c in range(3)], axis=0)
iso = float(sys.argv[2])
print(int(((nlo < iso) & (iso <= nhi)).sum()))
`,
      out,
      String(iso),
    ],
    { encoding: 'utf8' },
  );
  return Number(printed.trim());
}

test("a second isovalue reads only the bricks whose learnt ranges hold it (zfpy's at the store's rate) and fetches none again", async ({
  page,
}) => {
  test.setTimeout(300_000);
  const logged = watchErrors(page);
  await openApp(page, '/?store=/stores/neghip-zstd.zarr#iso=80.5&rate=8');
  await level0Shown(page);
  // every brick of level 0 read once (no ranges yet: the first surface of a level reads it whole), and its range learnt
  await expect(page.locator('#store-section dd[data-k="value-range"]')).not.toContainText('provisional', { timeout: 60_000 });
  type Levels = { chunksFetched: number; levels: { chunks: number; chunksFetched: number; chunksShown: number }[] };
  const state = () => page.evaluate(() => (window as unknown as { zfpisoStore: Levels }).zfpisoStore);
  const first = await state();
  expect(first.levels[0].chunksShown).toBe(first.levels[0].chunks);
  sidecarRange('8');
  const needed = neededByRanges('8', 200.5);
  expect(needed).toBeGreaterThan(0);
  expect(needed).toBeLessThan(first.levels[0].chunks);
  await setIsovalue(page, 200.5);
  await level0Shown(page);
  const second = await state();
  // the plan used the learnt ranges: exactly the bricks zfpy's ranges say the surface needs, none fetched again
  expect(second.levels[0].chunksShown).toBe(needed);
  expect(second.chunksFetched).toBe(first.chunksFetched);
  expect(logged.filter((e) => !/status of 404/.test(e))).toEqual([]);
});
