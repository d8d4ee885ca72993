// Playback of a store's time points (issue 47): a converted series (t = 6,
// 32^3 uint8, a ball moving and growing: tests/fixtures/series-e2e.py, then
// `convert 'step_*.raw' --time --time-step 0.5 --time-unit second`) opened by
// URL. Step forward and back (buttons, Alt+arrows), play with loop (wraps
// 5 -> 0), change the isovalue while playing (it keeps playing at the new
// one), play without loop (stops at the last), and the link reopened at t=5.
// Each time point drawn is whole (level 0, never a coarser level of a new
// time point) with the CLI's triangles at that time point and isovalue; the
// camera stays as it was; no page error.
import { execFileSync } from 'node:child_process';
import { mkdirSync, mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { expect, type Page, test } from '@playwright/test';
import { E2E_STORES_DIR, runCli } from './cli.ts';
import { openApp, watchErrors } from './page.ts';
import { trianglesShown } from './volume-page.ts';

const root = fileURLToPath(new URL('../../', import.meta.url));
const NAME = 'series-e2e.zarr';
/** CLI triangles at level 0 per `${t}|${iso}`. */
const truth = new Map<string, number>();

test.beforeAll(async () => {
  const work = mkdtempSync(join(tmpdir(), 'series-e2e-'));
  execFileSync(join(root, '.venv-converter/bin/python'), [join(root, 'tests/fixtures/series-e2e.py'), work], { timeout: 60_000 });
  const out = join(E2E_STORES_DIR, NAME);
  rmSync(out, { recursive: true, force: true });
  mkdirSync(E2E_STORES_DIR, { recursive: true });
  execFileSync(
    process.execPath,
    [
      join(root, 'scripts/convert.mjs'),
      join(work, 'step_*_32x32x32_uint8.raw'),
      '--time',
      '--time-step',
      '0.5',
      '--time-unit',
      'second',
      '--chunk',
      '16',
      '--rate',
      '8',
      '--out',
      out,
      '--quiet',
    ],
    { timeout: 120_000 },
  );
  rmSync(work, { recursive: true, force: true });
  const cli = await runCli<{ isosurfaces: { time: number; iso: number; triangles: number }[] }>([
    'extract',
    out,
    '--level',
    '0',
    '--time',
    '0:6',
    '--iso',
    '100,60',
  ]);
  for (const r of cli.isosurfaces) truth.set(`${r.time}|${r.iso}`, r.triangles);
});

interface Playback {
  index: number;
  count: number;
  playing: boolean;
  busy: boolean;
  loop: boolean;
  achievedFps: number | null;
  framesShown: number;
}
const playback = (page: Page) =>
  page.evaluate(() => (window as unknown as { zfpisoStore?: { playback?: unknown } }).zfpisoStore?.playback) as Promise<Playback>;

/** Waits until time point `t` is on screen whole and nothing is on its way. */
async function settledAt(page: Page, t: number, iso: number): Promise<void> {
  await page.waitForFunction(
    ({ t, iso }) => {
      const s = (window as unknown as { zfpisoStore?: { done: boolean; shownLevel: number; playback?: Playback } }).zfpisoStore;
      const p = s?.playback;
      return s?.done === true && s.shownLevel === 0 && p?.index === t && !p.busy && !p.playing && window.zfpiso?.stats?.isovalue === iso;
    },
    { t, iso },
    { timeout: 60_000 },
  );
  expect(await trianglesShown(page)).toBe(truth.get(`${t}|${iso}`));
}

/**
 * Watches every publication of the store's state from now on
 * (window.zfpisoStore is set anew each time): `installs`, per volume
 * installed, the time point, level and isovalue the first publication after
 * it gives; `shownAhead`, per time point, the last state of it once done:
 * its level, what was fetched ahead for it and the chunks its session fetched.
 */
async function recordPublished(page: Page): Promise<void> {
  await page.evaluate(() => {
    type S = {
      shownLevel: number | null;
      chunksFetched: number;
      done: boolean;
      playback?: { index: number; prefetch: { shown: unknown } };
    };
    const w = window as unknown as { installs: { t: number; level: number | null; iso?: number }[]; shownAhead: Record<number, unknown> };
    w.installs = [];
    w.shownAhead = {};
    let loads = window.zfpiso!.loads;
    let current = (window as unknown as { zfpisoStore?: S }).zfpisoStore;
    Object.defineProperty(window, 'zfpisoStore', {
      configurable: true,
      get: () => current,
      set: (s: S) => {
        current = s;
        const t = s.playback?.index ?? -1;
        if (s.done) w.shownAhead[t] = { t, level: s.shownLevel, shown: s.playback?.prefetch.shown ?? null, chunks: s.chunksFetched };
        const now = window.zfpiso!.loads;
        if (now === loads) return;
        loads = now;
        w.installs.push({ t, level: s.shownLevel, iso: window.zfpiso!.iso });
      },
    });
  });
}
/** Moves the time slider to `t` and lets go. */
const slideTo = (page: Page, t: number) =>
  page.locator('#store-playback input[data-play="time"]').evaluate((el: HTMLInputElement, t) => {
    el.value = String(t);
    el.dispatchEvent(new Event('input', { bubbles: true }));
    el.dispatchEvent(new Event('change', { bubbles: true }));
  }, t);
const installs = (page: Page) =>
  page.evaluate(() => (window as unknown as { installs: { t: number; level: number | null; iso?: number }[] }).installs);

test('play, pause, step, loop, isovalue while playing, the link at t=5', async ({ page }) => {
  test.setTimeout(120_000);
  const errors = watchErrors(page);
  await openApp(page, `/?store=/stores/${NAME}#iso=100`);
  await settledAt(page, 0, 100);
  const label = page.locator('#store-playback [data-k="time"]');
  await expect(page.locator('#store-playback')).toBeVisible();
  await expect(label).toHaveText('t = 0 of 6 (0 second)');
  await recordPublished(page);
  const camera = await page.evaluate(() => window.zfpiso!.camera!());

  // step forward and back: the buttons, and Alt+arrows anywhere but a text field
  await page.locator('#store-playback [data-play="forward"]').click();
  await settledAt(page, 1, 100);
  await expect(label).toHaveText('t = 1 of 6 (0.5 second)');
  await page.waitForFunction(() => location.hash.includes('t=1'));
  await page.locator('#view').focus();
  await page.keyboard.press('Alt+ArrowRight');
  await settledAt(page, 2, 100);
  await page.keyboard.press('Alt+ArrowLeft');
  await settledAt(page, 1, 100);
  await page.locator('#store-playback [data-play="back"]').click();
  await settledAt(page, 0, 100);
  // at the first time point without loop, back stays there
  await page.locator('#store-playback [data-play="back"]').click();
  expect((await playback(page)).index).toBe(0);

  // loop: from 4, play as fast as time points arrive, past 5 to 0, then pause (Space)
  await slideTo(page, 4);
  await settledAt(page, 4, 100);
  await page.locator('#store-playback [data-play="loop"]').check();
  await page.locator('#view').focus();
  await page.keyboard.press('Space');
  await page.waitForFunction(() => {
    const w = window as unknown as { installs: { t: number }[] };
    const ts = w.installs.map((i) => i.t);
    const at = ts.lastIndexOf(5);
    return at >= 0 && ts.slice(at + 1).includes(0) && ts.slice(at + 1).includes(1);
  });
  await page.keyboard.press('Space');
  let p = await playback(page);
  expect(p.playing).toBe(false);
  await page.waitForFunction(() => (window as unknown as { zfpisoStore: { playback: Playback } }).zfpisoStore.playback.busy === false);
  p = await playback(page);
  await settledAt(page, p.index, 100);

  // the isovalue changed while playing: playback goes on at the new one
  await page.locator('#store-playback [data-play="toggle"]').click();
  await page.waitForFunction(() => (window as unknown as { zfpisoStore: { playback: Playback } }).zfpisoStore.playback.playing);
  await page.locator('#iso-value').fill('60');
  await page.locator('#iso-value').press('Enter');
  const before = (await installs(page)).length;
  await page.waitForFunction(
    (n) => (window as unknown as { installs: { iso?: number }[] }).installs.slice(n).filter((i) => i.iso === 60).length >= 3,
    before,
  );
  await page.locator('#store-playback [data-play="toggle"]').click();
  await page.waitForFunction(() => (window as unknown as { zfpisoStore: { playback: Playback } }).zfpisoStore.playback.busy === false);
  p = await playback(page);
  expect(p.achievedFps).toBeGreaterThan(0);
  await settledAt(page, p.index, 60);

  // without loop, playback at 10 time points a second stops at the last one
  await page.locator('#store-playback [data-play="loop"]').uncheck();
  await page.locator('#store-playback [data-play="fps"]').selectOption('10');
  await slideTo(page, 3);
  await settledAt(page, 3, 60);
  await page.locator('#store-playback [data-play="toggle"]').click();
  await settledAt(page, 5, 60);
  await expect(page.locator('#store-playback [data-k="playback-rate"]')).toContainText('of 10 asked');

  // every time point drawn was whole (level 0), the camera never moved
  const all = await installs(page);
  expect(all.length).toBeGreaterThanOrEqual(10);
  expect(all.filter((i) => i.level !== 0)).toEqual([]);
  expect(await page.evaluate(() => window.zfpiso!.camera!())).toEqual(camera);
  await page.waitForFunction(() => location.hash.includes('t=5') && location.hash.includes('iso=60'));

  // the link reopened at t=5
  await page.goto('about:blank');
  await openApp(page, `/?store=/stores/${NAME}#iso=100&t=5`);
  await settledAt(page, 5, 100);
  await expect(page.locator('#store-playback [data-k="time"]')).toHaveText('t = 5 of 6 (2.5 second)');
  expect(errors).toEqual([]);
});

test('another time point keeps the surfaces, the clip and the voxel size', async ({ page }) => {
  const errors = watchErrors(page);
  await openApp(page, `/?store=/stores/${NAME}#iso=100,60&op=1,0.4&clip=0,0,0,20,31,31&vox=1,1,2`);
  await page.waitForFunction(() => window.zfpiso?.surfaces?.entries.length === 2);
  await settledAt(page, 0, 100);
  const kept = () =>
    page.evaluate(() => ({
      surfaces: window.zfpiso!.surfaces!.entries.map((e) => ({ iso: e.iso, opacity: e.opacity, color: e.color })),
      clip: window.zfpiso!.clip,
      spacing: window.zfpiso!.volume!.spacing,
    }));
  const before = await kept();
  await page.locator('#store-playback [data-play="forward"]').click();
  await settledAt(page, 1, 100);
  await page.waitForFunction(() => window.zfpiso!.surfaces!.entries[1]?.triangles !== undefined);
  expect(await kept()).toEqual(before);
  // the other surface is of time point 1 too
  expect(await page.evaluate(() => window.zfpiso!.surfaces!.entries[1].triangles)).toBe(truth.get('1|60'));
  await page.waitForFunction(
    () => /vox=1,1,2/.test(location.hash) && /clip=0,0,0,20,31,31/.test(location.hash) && /t=1/.test(location.hash),
  );
  expect(errors).toEqual([]);
});

interface Prefetched {
  time: number;
  wanted: number;
  asked: number;
  arrived: number;
  bytes: number;
  full: boolean;
  done: boolean;
  error: string | null;
}

test('while playing, the next time point is fetched ahead; a bound too small for it still plays every time point whole and says so', async ({
  page,
}) => {
  test.setTimeout(120_000);
  const errors = watchErrors(page);
  const shownAhead = () =>
    page.evaluate(() =>
      Object.values(
        (window as unknown as { shownAhead: Record<number, { t: number; level: number | null; shown: Prefetched | null; chunks: number }> })
          .shownAhead,
      ),
    );
  for (const bound of [null, 0.01]) {
    await openApp(page, `/?store=/stores/${NAME}${bound === null ? '' : `&prefetch=${bound}`}#iso=100`);
    await settledAt(page, 0, 100);
    await recordPublished(page);
    await page.locator('#store-playback [data-play="toggle"]').click();
    await settledAt(page, 5, 100);
    const shown = (await shownAhead()).filter((s) => s.t > 0);
    // every time point after the first shown once, whole (level 0)
    expect(shown.map((s) => s.t)).toEqual([1, 2, 3, 4, 5]);
    expect(shown.filter((s) => s.level !== 0)).toEqual([]);
    for (const s of shown) {
      expect(s.shown).toMatchObject({ time: s.t, done: true, error: null });
      const p = s.shown!;
      if (bound === null) {
        // the whole time point was there ahead: its session fetched no chunk itself (the plan ahead was its plan)
        expect(p).toMatchObject({ full: false, asked: p.wanted, arrived: p.wanted });
        expect(p.wanted).toBeGreaterThan(0);
        expect(s.chunks).toBe(p.arrived);
      } else {
        // 10 KiB: two chunks ahead, the rest fetched when shown, none twice
        expect(p.full).toBe(true);
        expect(p.asked).toBeLessThan(p.wanted);
        expect(s.chunks).toBeGreaterThan(p.arrived);
      }
    }
    await expect(page.locator('#store-playback [data-k="playback-prefetch"]')).toContainText(
      bound === null ? 't = 5 was fetched ahead' : 'prefetch bound, the rest is fetched when shown',
    );
  }
  expect(errors).toEqual([]);
});
