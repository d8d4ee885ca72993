// The page holds one GPU budget through every change a user makes (issue 48),
// on stores written by zarr-python the way public collections are (uint8,
// zstd, 64^3 chunks in shards, no range arrays: tests/fixtures/ball-store.py):
// - a 1024^3 store at 1 GiB, orbited and zoomed, then the budget control to
//   256 MiB: within a few frames the page's GPU bytes are within it, and the
//   surface is still drawn; the refinement that follows stays within it;
// - ten switches between two stores (picked folders): the peak never passes
//   the budget, and each store holds the same bytes every time it is shown;
// - a store whose shard is refused, closed while its retry waits: no request
//   reaches the server after the close (the server's log, /stores/~log);
// - an orbit over a store on a slow link: the decode workers never hold more
//   bricks than the fetcher asks for at once, plus those a worker was already
//   reading when they were cancelled (an instrumented count);
// - a PLY exported while the camera moves is the mesh of a step that was on
//   screen (its triangle and vertex counts, read by NumPy, are one step's).
import { execFileSync } from 'node:child_process';
import { createHash } from 'node:crypto';
import { existsSync, mkdirSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { expect, type Page, test } from '@playwright/test';
import { runPython } from '../helpers/python.ts';
import { convertNeghipStore, E2E_STORES_DIR } from './cli.ts';
import { nonBackgroundFraction, openApp, watchErrors } from './page.ts';

const root = join(import.meta.dirname, '..', '..');
const MiB = 2 ** 20;
const BIG = 'ball1024.zarr';
const A = 'ball256a.zarr';
const B = 'ball256b.zarr';

interface StoreState {
  url: string;
  done: boolean;
  reason: string | null;
  cut: { final: boolean; levels: { level: number; drawn: number }[] } | null;
  gpu: { store: number; total: number; peak: number; budget: number };
  decodeQueue?: { queued: number; maxQueued: number };
  steps: { iso: number; triangles: number; vertices: number }[];
  stepsShown: number;
}
const storeState = (page: Page) => page.evaluate(() => (window as unknown as { zfpisoStore: StoreState }).zfpisoStore);
/** The refinement of `url` has ended with its whole cut on screen. */
const settled = (page: Page, url?: string, timeout = 300_000) =>
  page.waitForFunction(
    (u) => {
      const s = (window as unknown as { zfpisoStore?: StoreState }).zfpisoStore;
      return s?.done === true && s.cut?.final === true && (u === null || s.url === u);
    },
    url ?? null,
    { timeout },
  );
const frames = (page: Page) => page.evaluate(() => window.zfpiso!.framesDrawn());
/** The budget control, as a user sets it (MiB, committed). */
async function setBudget(page: Page, mib: number): Promise<void> {
  await page.locator('#budget-mb').evaluate((el, v) => {
    const input = el as HTMLInputElement;
    input.value = String(v);
    input.dispatchEvent(new Event('change', { bubbles: true }));
  }, mib);
}
/** Drags on the view (rotates), `steps` moves of (dx, dy) pixels. */
async function orbit(page: Page, dx: number, dy: number, steps = 6): Promise<void> {
  const box = (await page.locator('#view').boundingBox())!;
  const [x, y] = [box.x + box.width / 2, box.y + box.height / 2];
  await page.mouse.move(x, y);
  await page.mouse.down();
  for (let i = 1; i <= steps; i++) await page.mouse.move(x + (dx * i) / steps, y + (dy * i) / steps);
  await page.mouse.up();
}
/** Wheel steps toward the volume (negative: away from it). */
async function zoom(page: Page, wheelSteps: number): Promise<void> {
  const box = (await page.locator('#view').boundingBox())!;
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  for (let i = 0; i < Math.abs(wheelSteps); i++) {
    await page.mouse.wheel(0, wheelSteps > 0 ? -240 : 240);
    await page.waitForTimeout(60);
  }
}

test.beforeAll(() => {
  test.setTimeout(600_000);
  mkdirSync(E2E_STORES_DIR, { recursive: true });
  // made again when the writer or its arguments change (a marker holds what made it)
  const writer = join(root, 'tests/fixtures/ball-store.py');
  const write = (name: string, n: number, radius: number) => {
    const out = join(E2E_STORES_DIR, name);
    const made = createHash('sha256').update(readFileSync(writer)).update(`${n} ${radius}`).digest('hex');
    const marker = join(out, '.made-by');
    if (existsSync(marker) && readFileSync(marker, 'utf8') === made) return;
    rmSync(out, { recursive: true, force: true });
    execFileSync(join(root, '.venv-converter/bin/python'), [writer, String(n), out, String(radius)], { timeout: 600_000, stdio: 'ignore' });
    writeFileSync(marker, made);
  };
  write(BIG, 1024, 0.3);
  write(A, 256, 0.3);
  write(B, 256, 0.2);
});

/** zarr-python leaves out chunks of empty space: their 404s are the store's way of saying so, not errors. */
const realErrors = (logged: string[]) => logged.filter((e) => !/status of 404|Failed to load resource|net::ERR_/.test(e));

test('1 GiB, orbit and zoom, then 256 MiB: within a few frames the GPU bytes are within it, and the surface is still drawn', async ({
  page,
}) => {
  test.setTimeout(900_000);
  const logged = watchErrors(page);
  await openApp(page, `/?store=/stores/${BIG}#iso=100.5&cut=1&tol=2.5`);
  await setBudget(page, 1024);
  await settled(page);
  await orbit(page, 160, 60);
  await zoom(page, 3);
  await page.waitForTimeout(400);
  await settled(page);
  const big = await storeState(page);
  expect(big.gpu.budget).toBe(1024 * MiB);
  expect(big.gpu.peak).toBeLessThanOrEqual(1024 * MiB);
  // the budget that follows is below what the page holds now: lowering it must give memory back
  expect(big.gpu.total, 'GPU bytes at 1 GiB').toBeGreaterThan(256 * MiB);

  const stepsBefore = big.stepsShown;
  const before = await frames(page);
  await setBudget(page, 256);
  await page.waitForFunction((n) => window.zfpiso!.framesDrawn() >= n + 3, before, { timeout: 60_000 });
  const low = await storeState(page);
  expect(low.gpu.budget).toBe(256 * MiB);
  expect(low.gpu.total, 'GPU bytes three frames after the budget went to 256 MiB').toBeLessThanOrEqual(256 * MiB);
  await expect(page.locator('#budget-bar')).toHaveAttribute('title', /held on the GPU by the streamed store/);
  expect(await nonBackgroundFraction(page)).toBeGreaterThan(0.01);

  // the refinement for the new budget: every allocation since the change within it, a surface on screen
  await settled(page);
  const after = await storeState(page);
  // the copies drawn at the change were replaced by steps planned for the new budget
  expect(after.stepsShown).toBeGreaterThan(stepsBefore);
  expect(after.gpu.peak).toBeLessThanOrEqual(256 * MiB);
  expect(after.gpu.total).toBeLessThanOrEqual(256 * MiB);
  expect(after.cut!.levels.reduce((a, l) => a + l.drawn, 0)).toBeGreaterThan(0);
  expect(await nonBackgroundFraction(page)).toBeGreaterThan(0.01);
  expect(realErrors(logged)).toEqual([]);
  const m = (b: number) => (b / MiB).toFixed(1);
  console.log(
    `page budget: at 1 GiB ${m(big.gpu.total)} MiB held (peak ${m(big.gpu.peak)}); three frames after 256 MiB: ${m(low.gpu.total)}; ` +
      `refined again: ${m(after.gpu.total)} (peak since the change ${m(after.gpu.peak)})`,
  );
});

test('ten switches between two stores: the peak never passes the budget, each store holds the same bytes every time', async ({ page }) => {
  test.setTimeout(900_000);
  const logged = watchErrors(page);
  await openApp(page, '/#iso=100.5&cut=1&tol=0.75');
  await setBudget(page, 96);
  const pick = async (name: string) => {
    await page.locator('input[webkitdirectory]').setInputFiles(join(E2E_STORES_DIR, name));
    await settled(page, name);
    return storeState(page);
  };
  const held: Record<string, number[]> = { [A]: [], [B]: [] };
  let peak = 0;
  for (let k = 0; k <= 10; k++) {
    const name = k % 2 === 0 ? A : B;
    const st = await pick(name);
    expect(st.gpu.budget).toBe(96 * MiB);
    peak = Math.max(peak, st.gpu.peak);
    held[name].push(st.gpu.total);
    // nothing of the store it replaced is held any more
    expect(st.gpu.total).toBe(st.gpu.store);
  }
  expect(peak).toBeLessThanOrEqual(96 * MiB);
  console.log(`ten switches at 96 MiB: peak ${(peak / MiB).toFixed(1)} MiB; ${A} ${held[A].join(', ')} B; ${B} ${held[B].join(', ')} B`);
  expect(new Set(held[A]).size, `bytes held by ${A}: ${held[A]}`).toBe(1);
  expect(new Set(held[B]).size, `bytes held by ${B}: ${held[B]}`).toBe(1);
  expect(realErrors(logged)).toEqual([]);
});

test('a store closed while a refused chunk waits to be tried again: no request reaches the server after the close', async ({ page }) => {
  test.setTimeout(300_000);
  const name = 'neghip-close.zarr';
  convertNeghipStore(name);
  // the level-0 shard in the middle of the volume answers 403: the coarser level stays and the chunk is tried again later
  await openApp(page, `/?store=/stores/~faults(rate=1;seed=1;kinds=403;match=${name}%2F0%2Fc%2F1%2F1%2F1)/${name}#iso=80`);
  await page.waitForFunction(
    () => /trying again in/.test((window as unknown as { zfpisoStore?: StoreState }).zfpisoStore?.reason ?? ''),
    null,
    {
      timeout: 240_000,
    },
  );
  await page.locator('#load-default').click();
  await page.waitForFunction(
    () => (window as unknown as { zfpiso: { volume?: { kind: string } } }).zfpiso.volume?.kind === 'default',
    null,
    {
      timeout: 120_000,
    },
  );
  const log = () =>
    page.evaluate(async () => (await (await fetch('/stores/~log')).json()) as { now: number; requests: { ms: number; path: string }[] });
  const closedAt = (await log()).now;
  // the cool-down (5 s) passes, and more
  await page.waitForTimeout(9_000);
  const late = (await log()).requests.filter((r) => r.ms > closedAt && r.path.includes(name));
  expect(late).toEqual([]);
});

test('an orbit over a store on a slow link: the decode workers hold no more bricks than are asked for', async ({ page }) => {
  test.setTimeout(600_000);
  const logged = watchErrors(page);
  // every request held back 0.2-1 s: the camera moves on while bricks are on their way
  await openApp(page, `/?store=/stores/~faults(rate=1;seed=3;kinds=slow)/${BIG}#iso=100.5&cut=1&tol=2.5`);
  const workers = await page.evaluate(() => Math.max(1, Math.min(4, (navigator.hardwareConcurrency ?? 2) - 1)));
  // in close and out again, and around: each move wants other bricks than the ones on their way
  for (let i = 0; i < 6; i++) {
    await zoom(page, 4);
    await page.waitForTimeout(300);
    await orbit(page, i % 2 === 0 ? 140 : -120, 30, 3);
    await page.waitForTimeout(300);
    await zoom(page, -4);
    await page.waitForTimeout(300);
  }
  // the replies of what was being read when the camera stopped say what the workers held
  await page.waitForTimeout(2000);
  const st = await storeState(page);
  expect(st.decodeQueue).toBeDefined();
  // the fetcher asks for 8 at once; a brick already being read when cancelled finishes (3 per worker at most)
  const bound = 8 + 3 * workers;
  expect(st.decodeQueue!.maxQueued).toBeLessThanOrEqual(bound);
  expect(st.decodeQueue!.queued).toBeLessThanOrEqual(bound);
  console.log(`decode workers on a slow link: at most ${st.decodeQueue!.maxQueued} bricks held (bound ${bound}, ${workers} worker(s))`);
  expect(realErrors(logged)).toEqual([]);
});

test('a PLY exported while the camera moves is the mesh of a step that was on screen', async ({ page }) => {
  test.setTimeout(600_000);
  const logged = watchErrors(page);
  await openApp(page, `/?store=/stores/${A}#iso=100.5&cut=1&tol=0.75`);
  await settled(page);
  // the camera goes on moving (new steps showing) while the export reads
  let moving = true;
  const mover = (async () => {
    for (let i = 0; moving && i < 40; i++) {
      await orbit(page, i % 2 === 0 ? 90 : -90, 20, 2);
      await page.waitForTimeout(80);
    }
  })();
  await page.waitForTimeout(500);
  // the button pressed from the keyboard's side: the mouse is busy turning the camera
  const [download] = await Promise.all([
    page.waitForEvent('download', { timeout: 300_000 }),
    page.evaluate(() => (document.getElementById('save-ply') as HTMLButtonElement).click()),
  ]);
  moving = false;
  await mover;
  const path = (await download.path())!;
  const counts = JSON.parse(
    runPython(
      `
import sys, json
from ply import read_ply
v, f = read_ply(sys.argv[1])
assert f.min() >= 0 and f.max() < len(v)
print(json.dumps({'vertices': len(v), 'triangles': len(f), 'lo': float(v.min()), 'hi': float(v.max())}))
`,
      [path],
    ),
  ) as { vertices: number; triangles: number; lo: number; hi: number };
  const st = await storeState(page);
  expect(counts.triangles).toBeGreaterThan(0);
  const shown = st.steps.filter((s) => s.iso === 100.5).map((s) => `${s.triangles}/${s.vertices}`);
  expect(shown, 'the steps shown (triangles/vertices)').toContain(`${counts.triangles}/${counts.vertices}`);
  expect(counts.lo).toBeGreaterThanOrEqual(-0.5);
  expect(counts.hi).toBeLessThanOrEqual(256);
  expect(realErrors(logged)).toEqual([]);
});
