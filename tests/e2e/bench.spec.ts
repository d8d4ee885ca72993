// The in-page benchmark: a short run (10 isovalues per sequence) shows its
// progress, a summary table and a chart, and offers JSON and CSV whose
// records are the CLI's for the same volume, seed and range. With draw=rays
// (issue 46) a frame is drawn and timed per surface: the table shows the
// frame and image times.
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { expect, test } from '@playwright/test';
import type { BenchRecord } from '../../src/bench/harness.ts';
import { runCli, SHARED_VOLUMES_DIR } from './cli.ts';
import { SHARED_VOLUMES } from './volume-page.ts';
import { watchErrors } from './page.ts';

const FILE = 'hydrogen_atom_128x128x128_float32.rate8.zfp';
const SEED = 7;
const COUNT = 10;
const RANGE: [number, number] = [5.5, 120];

/** What must match between page and CLI (times differ). */
const comparable = (r: BenchRecord) => ({
  mode: r.mode,
  index: r.index,
  iso: r.iso,
  activeBlocks: r.activeBlocks,
  newBlocks: r.newBlocks,
  occupiedBlocks: r.occupiedBlocks,
  triangles: r.triangles,
  hitRate: r.hitRate,
  discarded: r.discarded,
});

test("a short benchmark runs in the page and its records are the CLI's", async ({ page }) => {
  test.setTimeout(300_000);
  const cli = runCli<{ records: BenchRecord[] }>([
    'bench',
    join(SHARED_VOLUMES_DIR, FILE),
    '--modes',
    'random,sweep-up,sweep-down',
    '--count',
    String(COUNT),
    '--seed',
    String(SEED),
    '--range',
    RANGE.join(','),
  ]);
  await page.goto(`/?url=${SHARED_VOLUMES}${FILE}`);
  await expect(page.locator('body')).toHaveAttribute('data-status', 'ready', { timeout: 120_000 });

  await page.locator('#bench-section summary').click();
  await page.locator('#bench-count').fill(String(COUNT));
  await page.locator('#bench-seed').fill(String(SEED));
  await page.locator('#bench-lo').fill(String(RANGE[0]));
  await page.locator('#bench-hi').fill(String(RANGE[1]));
  await page.locator('#bench-run').click();
  // Progress while it runs; the isovalue controls are locked.
  await expect(page.locator('#bench-progress')).toBeVisible();
  await expect(page.locator('#bench-status')).toContainText(/random|sweep/);
  await expect(page.locator('#iso-slider')).toBeDisabled();
  await page.waitForFunction(() => window.zfpiso!.bench !== undefined && !window.zfpiso!.benchRunning, null, { timeout: 240_000 });
  await expect(page.locator('#bench-status')).toHaveText(`Done: ${3 * COUNT} surfaces.`);
  await expect(page.locator('#iso-slider')).toBeEnabled();

  // The summary table: one column per sequence.
  const table = page.locator('#bench-table');
  await expect(table.locator('thead th')).toHaveText(['mean over', 'random', 'sweep-up', 'sweep-down']);
  await expect(table.locator('tbody tr').first().locator('td')).toHaveText([String(COUNT - 1), String(COUNT - 1), String(COUNT - 1)]);
  // The chart is drawn (pixels on the canvas).
  const inked = await page.locator('#bench-chart').evaluate((c: HTMLCanvasElement) => {
    const d = c.getContext('2d')!.getImageData(0, 0, c.width, c.height).data;
    let n = 0;
    for (let i = 3; i < d.length; i += 4) if (d[i] > 0) n++;
    return n / (c.width * c.height);
  });
  expect(inked).toBeGreaterThan(0.02);

  // JSON download: per-isovalue records and per-mode summaries.
  const [json] = await Promise.all([page.waitForEvent('download'), page.locator('#bench-json').click()]);
  expect(json.suggestedFilename()).toBe(`${FILE}_bench.json`);
  const result = JSON.parse(readFileSync((await json.path())!, 'utf8')) as {
    records: BenchRecord[];
    summaries: { mode: string; count: number }[];
    options: { seed: number; count: number; range: number[] };
  };
  expect(result.options).toMatchObject({ seed: SEED, count: COUNT, range: RANGE });
  expect(result.records).toHaveLength(3 * COUNT);
  expect(result.summaries.map((s) => [s.mode, s.count])).toEqual([
    ['random', COUNT - 1],
    ['sweep-up', COUNT - 1],
    ['sweep-down', COUNT - 1],
  ]);

  const [csv] = await Promise.all([page.waitForEvent('download'), page.locator('#bench-csv').click()]);
  const lines = readFileSync((await csv.path())!, 'utf8')
    .trim()
    .split('\n');
  expect(lines[0]).toBe('mode,index,iso,gpuMs,wallMs,hitRate,activeBlocks,newBlocks,occupiedBlocks,triangles,discarded');
  expect(lines).toHaveLength(1 + 3 * COUNT);

  // Same isovalues, blocks, cache behaviour and triangles as the CLI.
  const headless = await cli;
  expect(result.records.map(comparable)).toEqual(headless.records.map(comparable));
});

test('draw=rays: the benchmark times a ray-cast frame per surface; the table shows frame and image times', async ({ browser }) => {
  test.setTimeout(180_000);
  // a smaller canvas: a ray-cast frame on SwiftShader costs seconds at the default viewport
  const page = await browser.newPage({ viewport: { width: 800, height: 480 } });
  const errors = watchErrors(page);
  await page.goto(`/?url=${SHARED_VOLUMES}${FILE}#iso=20&draw=rays`);
  await expect(page.locator('body')).toHaveAttribute('data-status', 'ready', { timeout: 120_000 });
  await page.waitForFunction(() => window.zfpiso!.raysDrawn === true, null, { timeout: 60_000 });
  await page.locator('#bench-section summary').click();
  for (const mode of ['sweep-up', 'sweep-down']) await page.locator(`#bench-section input[value="${mode}"]`).uncheck();
  await page.locator('#bench-count').fill('3');
  await page.locator('#bench-seed').fill(String(SEED));
  await page.locator('#bench-run').click();
  await page.waitForFunction(() => window.zfpiso!.bench !== undefined && !window.zfpiso!.benchRunning, null, { timeout: 150_000 });
  await expect(page.locator('#bench-status')).toHaveText('Done: 3 surfaces.');
  const bench = (await page.evaluate(() => window.zfpiso!.bench)) as unknown as { draw: string; records: BenchRecord[] };
  expect(bench.draw).toBe('rays');
  expect(bench.records).toHaveLength(3);
  for (const r of bench.records) {
    expect(r.frameMs).toBeGreaterThan(0);
    expect(r.imageMs).toBeCloseTo(r.gpuMs + r.frameMs!, 6);
  }
  // the rows of frame and image time, a time in each
  const rows = page.locator('#bench-table tbody tr');
  await expect(rows.locator('th')).toContainText(['mean frame', 'median frame', 'mean image', 'median image']);
  for (const name of ['mean frame', 'mean image']) await expect(rows.filter({ hasText: name }).locator('td')).toHaveText(/^\d[\d.]* m?s$/);
  expect(await page.evaluate(() => window.zfpiso!.raysDrawn)).toBe(true);
  expect(errors).toEqual([]);
  await page.close();
});
