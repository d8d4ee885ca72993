// Several surfaces of one volume: add a second surface and move it while the
// first stays as it was (its copy keeps its triangles; the CLI, held to VTK
// by the unit tests, gives the same counts for both isovalues), the cache
// shared (going back to the first decodes nothing), a see-through surface,
// Measure gives every visible surface (downloaded as CSV and JSON),
// the link reopens the same surfaces, a surface can be removed (a link with
// an isovalue outside the volume's values: clip.spec.ts).
import { readFileSync } from 'node:fs';
import { expect, test } from '@playwright/test';
import { runCli } from './cli.ts';
import { openApp, waitForFrames } from './page.ts';
import { setIsovalue } from './volume-page.ts';

const surfacesOf = (page: import('@playwright/test').Page) => page.evaluate(() => window.zfpiso!.surfaces!);

test('two surfaces: each keeps its own, one see-through, measured; the link reopens them', async ({ page, context }) => {
  await openApp(page);
  await setIsovalue(page, 0.43);
  const cli = await runCli<{ isosurfaces: { triangles: number }[] }>(['extract', 'default', '--iso', '0.43,0.6']);
  const [t043, t06] = cli.isosurfaces.map((r) => r.triangles);

  await page.locator('#add-surface').click();
  await expect(page.locator('#surface-list li')).toHaveCount(2);
  await page.waitForFunction(() => window.zfpiso!.surfaces!.selected === 1);
  await setIsovalue(page, 0.6);
  await waitForFrames(page, 1);
  let s = await surfacesOf(page);
  expect(s.entries.map((e) => e.iso)).toEqual([0.43, 0.6]);
  expect(s.entries.map((e) => e.triangles)).toEqual([t043, t06]);
  expect(s.copyBytes).toBeGreaterThan(0);
  expect(s.entries[0].color).not.toEqual(s.entries[1].color);

  // moving the second surface leaves the first as it was
  await setIsovalue(page, 0.62);
  s = await surfacesOf(page);
  expect(s.entries[0].triangles).toBe(t043);

  // back to the first: computed again from the cache, nothing decoded
  await page.locator('#surface-list li').nth(0).locator('input[type=radio]').check();
  await page.waitForFunction(() => window.zfpiso!.surfaces!.selected === 0 && window.zfpiso!.stats!.isovalue === Math.fround(0.43));
  expect(await page.evaluate(() => window.zfpiso!.stats!.newBlocks)).toBe(0);
  await expect(page.locator('#iso-value')).toHaveValue('0.4300');

  // the second see-through: drawn (depth peeled) and in the link
  await page.locator('#surface-list li').nth(1).locator('input[type=range]').fill('0.35');
  await waitForFrames(page, 2);
  expect((await surfacesOf(page)).entries[1].opacity).toBe(0.35);
  await page.waitForFunction(() => location.hash.includes('iso=0.43,0.62') && location.hash.includes('op=1,0.35'));

  // Measure: every visible surface; the CSV has a row each, the JSON the same figures
  await page.locator('#measure-surface').click();
  await page.waitForFunction(() => (window.zfpiso!.measures?.length ?? 0) === 2);
  const measures = (await page.evaluate(() => window.zfpiso!.measures))!;
  expect(measures.map((m) => [m.iso, m.triangles, m.selected])).toEqual([
    [0.43, t043, true],
    [0.62, (await surfacesOf(page)).entries[1].triangles, false],
  ]);
  const [csv] = await Promise.all([page.waitForEvent('download'), page.locator('#measures-csv').click()]);
  const rows = readFileSync((await csv.path())!, 'utf8')
    .trim()
    .split('\n');
  expect(rows[0]).toBe('iso,selected,color,opacity,triangles,area,enclosed_volume,open_edges,units');
  expect(rows.slice(1).map((r) => r.split(',').slice(0, 5))).toEqual(
    measures.map((m) => [
      String(m.iso),
      m.selected ? '1' : '0',
      expect.stringMatching(/^[0-9a-f]{6}$/),
      String(m.opacity),
      String(m.triangles),
    ]),
  );
  const [json] = await Promise.all([page.waitForEvent('download'), page.locator('#measures-json').click()]);
  const record = JSON.parse(readFileSync((await json.path())!, 'utf8'));
  expect(record.surfaces.map((m: { area: number }) => m.area)).toEqual(measures.map((m) => m.area));
  expect(record.volume.dims).toEqual([128, 128, 128]);

  // a budget too small for the copies: they go (the surface stays listed, not drawn), with a message
  const mb = await page.locator('#budget-mb').inputValue();
  await page.locator('#budget-mb').fill('1');
  await page.locator('#budget-mb').press('Enter');
  await page.waitForFunction(() => window.zfpiso!.surfaces!.copyBytes === 0);
  await expect(page.locator('#messages')).toContainText('The surfaces at 0.62 are no longer kept within 1 MiB');
  await expect(page.locator('#surface-list li').nth(1)).toContainText('not kept');
  await page.locator('#budget-mb').fill(mb);
  await page.locator('#budget-mb').press('Enter');

  const other = await context.newPage();
  await openApp(other, page.url().replace(/^https?:\/\/[^/]+/, ''));
  await other.waitForFunction(() => window.zfpiso!.surfaces!.entries.length === 2 && window.zfpiso!.surfaces!.selected === 0, null, {
    timeout: 120_000,
  });
  await other.waitForFunction(() => window.zfpiso!.stats!.isovalue === Math.fround(0.43));
  const reopened = await surfacesOf(other);
  expect(reopened.entries.map((e) => [e.iso, e.opacity])).toEqual([
    [0.43, 1],
    [0.62, 0.35],
  ]);
  expect(reopened.entries[0].triangles).toBe(t043);
  // colours travel as rrggbb
  const byte = (c: number[] | undefined) => c?.map((v) => Math.round(v * 255));
  expect(byte(reopened.entries[0].color)).toEqual(byte(s.entries[0].color));
  expect(byte(reopened.entries[1].color)).toEqual(byte(s.entries[1].color));
  await other.close();

  // remove the first: the second takes the slider
  await page.locator('#surface-list li').nth(0).locator('button[title=Remove]').click();
  await expect(page.locator('#surface-list li')).toHaveCount(1);
  expect((await surfacesOf(page)).entries.map((e) => e.iso)).toEqual([0.62]);
  expect((await surfacesOf(page)).copyBytes).toBe(0);
});
