// The page on a network that misbehaves and a GPU that goes away:
// - a store behind the preview server's faulty prefix (scripts/store-faults.ts:
//   30% of requests fail as object stores and proxies fail, every kind of
//   request) ends at level 0 with exactly the CLI's fault-free triangles;
// - a shard that is refused (403) leaves the coarser level on screen, the
//   reason names the chunk and the cause, and it is asked for again later;
// - a lost device (the page's loseDevice hook destroys it, as a driver reset
//   would lose it) gives a new device, and what was on screen opens again at
//   the same isovalue and view: the built-in volume, and a store mid-stream.
import { expect, type Page, test } from '@playwright/test';
import { convertNeghipStore, runCli } from './cli.ts';
import { openApp, watchErrors } from './page.ts';
import { trianglesShown } from './volume-page.ts';

const NAME = 'neghip-resilience.zarr';
let store = '';

interface StoreState {
  done: boolean;
  shownLevel: number | null;
  shownLevels: number[];
  reason: string | null;
  retries: number;
  failedRequests: number;
  gpu: { total: number; budget: number };
}
const storeState = (page: Page) => page.evaluate(() => (window as unknown as { zfpisoStore: unknown }).zfpisoStore) as Promise<StoreState>;
const storeDone = (page: Page) =>
  page.waitForFunction(() => (window as unknown as { zfpisoStore?: { done: boolean } }).zfpisoStore?.done === true, null, {
    timeout: 240_000,
  });
/** Console errors other than the browser's own lines about failed requests (the faults are on purpose). */
const realErrors = (errors: string[]) => errors.filter((e) => !/Failed to load resource|net::ERR_/.test(e));

test.beforeAll(() => {
  store = convertNeghipStore(NAME);
});

test('30% of requests failing: level 0 with exactly the fault-free triangles, for two seeds', async ({ page }) => {
  test.setTimeout(400_000);
  const errors = watchErrors(page);
  const cli = await runCli<{ isosurfaces: { triangles: number }[] }>(['extract', store, '--level', '0', '--iso', '80']);
  for (const seed of [1, 2]) {
    await openApp(page, `/?store=/stores/~faults(rate=0.3;seed=${seed})/${NAME}#iso=80`);
    await storeDone(page);
    const st = await storeState(page);
    expect(st.reason).toBeNull();
    expect(st.shownLevels).toEqual([3, 2, 1, 0]);
    expect(st.retries).toBeGreaterThan(0);
    expect(st.failedRequests).toBe(0);
    expect(st.gpu.total).toBeLessThanOrEqual(st.gpu.budget);
    expect(await trianglesShown(page)).toBe(cli.isosurfaces[0].triangles);
    await expect(page.locator('#store-section dd[data-k="retries"]')).toHaveText(String(st.retries));
  }
  expect(realErrors(errors)).toEqual([]);
});

test('a refused shard: the coarser level stays, the reason names the chunk and the cause, and it is tried again', async ({ page }) => {
  test.setTimeout(300_000);
  // the level-0 shard of chunks (2..3, 2..3, 2..3), the middle of the volume, answers 403
  await openApp(page, `/?store=/stores/~faults(rate=1;seed=1;kinds=403;match=${NAME}%2F0%2Fc%2F1%2F1%2F1)/${NAME}#iso=80`);
  await storeDone(page);
  const st = await storeState(page);
  expect(st.shownLevel).toBe(1);
  expect(st.reason).toMatch(/level 0 chunk \([23], [23], [23]\): GET \/0\/c\/1\/1\/1 .*HTTP 403 .*\(trying again in \d+ s\)/);
  await expect(page.locator('#store-progress')).toContainText('level 1 shown');
  await expect(page.locator('#messages')).toContainText(/chunk \([23], [23], [23]\).*HTTP 403/);
  // the cool-down passes and the chunk is asked for again (refused again: the level stays)
  const failed = st.failedRequests;
  await page.waitForFunction(
    (n) => ((window as unknown as { zfpisoStore: { failedRequests: number } }).zfpisoStore.failedRequests ?? 0) > n,
    failed,
    { timeout: 30_000 },
  );
  // the retry is a refinement of the page's like any other: it ends, and the line says where it stopped again
  await storeDone(page);
  expect((await storeState(page)).shownLevel).toBe(1);
  await expect(page.locator('#store-progress')).toContainText('level 1 shown');
  expect((await storeState(page)).reason).toMatch(/HTTP 403 .*\(trying again in \d+ s\)/);
});

test('a lost device: a new one, and the built-in volume again at the same isovalue, surfaces and view', async ({ page }) => {
  test.setTimeout(300_000);
  const errors = watchErrors(page);
  await openApp(page, '/#iso=0.42,0.6&op=1,0.5&sel=0');
  const bothDrawn = () =>
    page.waitForFunction(
      () => {
        const s = window.zfpiso?.surfaces;
        return s?.entries.length === 2 && s.selected === 0 && s.entries.every((e) => e.triangles !== undefined);
      },
      null,
      { timeout: 120_000 },
    );
  await bothDrawn();
  await page.mouse.move(500, 300);
  await page.mouse.down();
  await page.mouse.move(560, 340, { steps: 5 });
  await page.mouse.up();
  const before = await page.evaluate(() => ({
    camera: window.zfpiso!.camera!(),
    iso: window.zfpiso!.stats!.isovalue,
    triangles: window.zfpiso!.stats!.triangles,
    loads: window.zfpiso!.loads,
    surfaces: window.zfpiso!.surfaces!.entries.map((e) => [e.iso, e.opacity, e.triangles]),
  }));
  await page.evaluate(() => window.zfpiso!.loseDevice!());
  await page.waitForFunction(
    (loads) => window.zfpiso!.deviceLosses === 1 && window.zfpiso!.status === 'ready' && window.zfpiso!.loads > loads,
    before.loads,
    { timeout: 120_000 },
  );
  // the other surface made again around the one the volume reopened with; the slider back on the first
  await bothDrawn();
  await page.waitForFunction((iso) => window.zfpiso!.stats!.isovalue === iso, before.iso, { timeout: 120_000 });
  const after = await page.evaluate(() => ({
    camera: window.zfpiso!.camera!(),
    iso: window.zfpiso!.stats!.isovalue,
    triangles: window.zfpiso!.stats!.triangles,
    frames: window.zfpiso!.framesDrawn(),
  }));
  expect(after.iso).toBe(before.iso);
  expect(after.triangles).toBe(before.triangles);
  expect(after.camera).toEqual(before.camera);
  expect(await page.evaluate(() => window.zfpiso!.surfaces!.entries.map((e) => [e.iso, e.opacity, e.triangles]))).toEqual(before.surfaces);
  await expect(page.locator('#messages')).toContainText('A new GPU device is being started');
  await expect(page.locator('#fatal')).toHaveCount(0);
  // it keeps drawing on the new device
  await page.keyboard.press(']');
  await page.waitForFunction((n) => window.zfpiso!.framesDrawn() > n, after.frames, { timeout: 60_000 });
  expect(errors).toEqual([]);
});

test('a lost device while a store streams: it opens again and ends at the same level-0 surface', async ({ page }) => {
  test.setTimeout(400_000);
  const errors = watchErrors(page);
  const cli = await runCli<{ isosurfaces: { triangles: number }[] }>(['extract', store, '--level', '0', '--iso', '80']);
  // slow answers keep it streaming long enough to lose the device on the way
  await openApp(page, `/?store=/stores/~faults(rate=0.5;seed=3;kinds=slow)/${NAME}#iso=80`);
  await page.waitForFunction(
    () => ((window as unknown as { zfpisoStore?: { shownLevels: number[] } }).zfpisoStore?.shownLevels.length ?? 0) >= 1,
    null,
    {
      timeout: 240_000,
    },
  );
  await page.evaluate(() => window.zfpiso!.loseDevice!());
  await page.waitForFunction(() => window.zfpiso!.deviceLosses === 1 && window.zfpiso!.status === 'ready', null, { timeout: 240_000 });
  await storeDone(page);
  const st = await storeState(page);
  expect(st.shownLevel).toBe(0);
  expect(st.reason).toBeNull();
  expect(await trianglesShown(page)).toBe(cli.isosurfaces[0].triangles);
  expect(await page.evaluate(() => window.zfpiso!.stats!.isovalue)).toBe(80);
  expect(realErrors(errors)).toEqual([]);
});
