// Series in (issue 47): numbered volume files picked together play as a time
// series through the page's store path. A raw series (5 time points of 48^3
// uint8, a ball moving along x and growing, written by NumPy) and a TIFF
// series (3 multi-page stacks written by tifffile): each time point drawn,
// stepping and playing to the end, has the triangles vtkFlyingEdges3D finds
// in zfpy's decode of NumPy's array of that time point at the rate the page
// chose (read from the link), which differ from time point to time point. A
// set whose second file is one plane short is refused naming that file, no
// page error, and the series on screen stays. Names that leave it open ask:
// Escape cancels, "Open the first only" opens one volume.
import { mkdtempSync, readdirSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { expect, type Page, test } from '@playwright/test';
import { runPython } from '../helpers/python.ts';
import { openApp, watchErrors } from './page.ts';
import { acceptVolumeForm, trianglesShown } from './volume-page.ts';

const work = mkdtempSync(join(tmpdir(), 'file-series-e2e-'));
test.afterAll(() => rmSync(work, { recursive: true, force: true }));

test.beforeAll(() => {
  runPython(
    `
import sys, os, numpy as np, tifffile
d = sys.argv[1]
def ball(n, nz, t, peak):
    z, y, x = np.mgrid[0:nz, 0:n, 0:n].astype(np.float32)
    cx, r = n * (0.3 + 0.08 * t), n * (0.15 + 0.02 * t)
    dist = np.sqrt((x - cx) ** 2 + (y - n / 2) ** 2 + (z - nz / 2) ** 2)
    return np.clip(np.round(peak / (1.0 + np.exp((dist - r) / 1.5))), 0, peak)
for sub in ('raw', 'tif', 'bad'): os.makedirs(f'{d}/{sub}')
for t in range(5):
    ball(48, 48, t, 200).astype(np.uint8).tofile(f'{d}/raw/ball_{t}_48x48x48_uint8.raw')
for t in range(3):
    tifffile.imwrite(f'{d}/tif/t{t + 1}.tif', ball(40, 24, t, 1000).astype(np.uint16))
ball(48, 48, 0, 200).astype(np.uint8).tofile(f'{d}/bad/bad_0_48x48x48_uint8.raw')
ball(48, 48, 1, 200).astype(np.uint8)[:-1].tofile(f'{d}/bad/bad_1_48x48x48_uint8.raw')
`,
    [work],
  );
});

/** Per time point: vtkFlyingEdges3D's triangles over zfpy's rate-R decode of the file's array (float32) at `iso`. */
function truth(files: string[], rate: number, iso: number): number[] {
  return JSON.parse(
    runPython(
      `
import sys, json, numpy as np, zfpy, tifffile, vtk
from vtk.util.numpy_support import numpy_to_vtk
rate, iso, files = float(sys.argv[1]), float(sys.argv[2]), sys.argv[3:]
out = []
for f in files:
    v = tifffile.imread(f) if f.endswith('.tif') else np.fromfile(f, np.uint8).reshape(48, 48, 48)
    dec = zfpy.decompress_numpy(zfpy.compress_numpy(np.ascontiguousarray(v.astype(np.float32)), rate=rate, write_header=True))
    img = vtk.vtkImageData(); img.SetDimensions(dec.shape[2], dec.shape[1], dec.shape[0])
    img.GetPointData().SetScalars(numpy_to_vtk(dec.ravel(), deep=1))
    m = vtk.vtkFlyingEdges3D(); m.SetInputData(img); m.SetValue(0, iso); m.ComputeNormalsOff(); m.Update()
    out.append(m.GetOutput().GetNumberOfPolys())
print(json.dumps(out))
`,
      [String(rate), String(iso), ...files],
    ),
  );
}

const inDir = (sub: string) =>
  readdirSync(join(work, sub))
    .sort((a, b) => a.localeCompare(b, 'en', { numeric: true }))
    .map((n) => join(work, sub, n));

interface Playback {
  index: number;
  count: number;
  playing: boolean;
  busy: boolean;
}
interface StoreState {
  url: string;
  done: boolean;
  shownLevel: number | null;
  playback?: Playback;
}
const storeState = (page: Page) => page.evaluate(() => (window as unknown as { zfpisoStore?: StoreState }).zfpisoStore ?? null);

/** Waits until time point `t` is on screen whole at `iso` with nothing on its way; its triangles. */
async function settledAt(page: Page, t: number, iso: number): Promise<number> {
  await page.waitForFunction(
    ({ t, iso }) => {
      const s = (window as unknown as { zfpisoStore?: StoreState }).zfpisoStore;
      const p = s?.playback;
      return s?.done === true && s.shownLevel === 0 && p?.index === t && !p.busy && !p.playing && window.zfpiso?.stats?.isovalue === iso;
    },
    { t, iso },
    { timeout: 60_000 },
  );
  return trianglesShown(page);
}

/** Picks `files`, waits for the series to open, sets `iso`; the rate the page chose (the link's rate=). */
async function openSeries(page: Page, files: string[], name: string, iso: number): Promise<number> {
  await page.setInputFiles('#file-input', files);
  await page.waitForFunction((name) => (window as unknown as { zfpisoStore?: StoreState }).zfpisoStore?.url === name, name, {
    timeout: 60_000,
  });
  await page.waitForFunction(() => (window as unknown as { zfpisoStore?: StoreState }).zfpisoStore?.done === true, null, {
    timeout: 60_000,
  });
  await page.locator('#iso-value').fill(String(iso));
  await page.locator('#iso-value').press('Enter');
  await settledAt(page, 0, iso);
  // The link is written 250 ms after a change: wait for the one that holds this iso (and so this series' rate, set
  // when it opened), not a previous series' link still in the address bar.
  await page.waitForFunction((iso) => new RegExp(`[#&]iso=${iso}(&|$)`).test(location.hash) && /rate=/.test(location.hash), iso);
  return Number(/rate=([\d.]+)/.exec(await page.evaluate(() => location.hash))![1]);
}

test('a numbered raw series and a TIFF series play; a mismatched set is refused by name', async ({ page }) => {
  test.setTimeout(170_000);
  const errors = watchErrors(page);
  await openApp(page);

  // raw: five numbered files, the shape in their names
  const raw = inDir('raw');
  const rawName = 'ball_0_48x48x48_uint8.raw … ball_4_48x48x48_uint8.raw (5 time points)';
  const rate = await openSeries(page, raw, rawName, 100);
  const want = truth(raw, rate, 100);
  expect(new Set(want).size).toBe(5); // the ball moves and grows: every time point its own surface
  await expect(page.locator('#store-playback [data-k="time"]')).toContainText('t = 0 of 5');
  expect(await trianglesShown(page)).toBe(want[0]);
  for (let t = 1; t < 5; t++) {
    await page.locator('#store-playback [data-play="forward"]').click();
    expect(await settledAt(page, t, 100), `time point ${t}`).toBe(want[t]);
  }
  // play from the first to the last (no loop: it stops there)
  await page.locator('#store-playback input[data-play="time"]').evaluate((el: HTMLInputElement) => {
    el.value = '0';
    el.dispatchEvent(new Event('input', { bubbles: true }));
    el.dispatchEvent(new Event('change', { bubbles: true }));
  });
  expect(await settledAt(page, 0, 100)).toBe(want[0]);
  await page.locator('#store-playback [data-play="toggle"]').click();
  expect(await settledAt(page, 4, 100)).toBe(want[4]);

  // TIFF: three 3-D stacks
  const tif = inDir('tif');
  const tifRate = await openSeries(page, tif, 't1.tif … t3.tif (3 time points)', 500);
  const tifWant = truth(tif, tifRate, 500);
  expect(await trianglesShown(page)).toBe(tifWant[0]);
  await page.locator('#store-playback [data-play="toggle"]').click();
  expect(await settledAt(page, 2, 500)).toBe(tifWant[2]);

  // a set whose second file is one plane short: refused naming it; the TIFF series stays on screen
  const loadsBefore = await page.evaluate(() => window.zfpiso!.loads);
  await page.setInputFiles('#file-input', inDir('bad'));
  await expect(page.locator('#messages')).toContainText(
    "bad_1_48x48x48_uint8.raw: 108,288 bytes; the series' shape 48×48×48 uint8 needs 110,592",
  );
  const after = await storeState(page);
  expect(after?.url).toBe('t1.tif … t3.tif (3 time points)');
  expect(after?.playback?.index).toBe(2);
  expect(await page.evaluate(() => window.zfpiso!.loads)).toBe(loadsBefore);
  expect(await trianglesShown(page)).toBe(tifWant[2]);

  // names that leave it open (not numbered alike): the page asks; Escape cancels, "the first only" opens one volume
  const unsure = [join(work, 'bad/bad_0_48x48x48_uint8.raw'), raw[3]];
  await page.setInputFiles('#file-input', unsure);
  const dialog = page.locator('#series-dialog');
  await expect(dialog).toBeVisible();
  await expect(dialog).toContainText('Open these 2 files as a time series');
  await page.keyboard.press('Escape');
  await expect(dialog).toBeHidden();
  expect((await storeState(page))?.url).toBe('t1.tif … t3.tif (3 time points)');
  await page.setInputFiles('#file-input', unsure);
  await dialog.getByRole('button', { name: 'Open the first only' }).click();
  await acceptVolumeForm(page); // as for any one raw file: its rate
  await page.waitForFunction((n) => window.zfpiso!.loads > n && !window.zfpiso!.loading, loadsBefore, { timeout: 60_000 });
  expect(await page.evaluate(() => window.zfpiso!.volume?.name)).toBe('bad_0_48x48x48_uint8.raw');
  expect(errors).toEqual([]);
});
