// Record (issue 47): a movie of a store's time points. A converted series
// (t = 6, 32^3 uint8, a ball moving and growing: tests/fixtures/series-e2e.py)
// opened by URL at t = 0; Record plays to t = 5 and records one video frame
// per time point, with a progress bar, then offers the WebM for download.
// The file is checked from outside the page's code: its bytes (the blob URL
// fetched in the page) walked as EBML here (header, DocType "webm", the
// track's codec and pixel size = the canvas's, the SimpleBlocks of the
// clusters: one per time point), and every block decoded by the browser's
// own WebCodecs VideoDecoder (6 frames at the canvas size, the ball's area
// growing frame by frame as it does over the time points). Cancel drops a
// recording half way; a browser without MediaRecorder says so. No page error.
import { execFileSync } from 'node:child_process';
import { existsSync, mkdirSync, mkdtempSync, renameSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { expect, type Page, test } from '@playwright/test';
import { E2E_STORES_DIR } from './cli.ts';
import { openApp, watchErrors } from './page.ts';

const root = fileURLToPath(new URL('../../', import.meta.url));
const NAME = 'record-e2e.zarr';

test.beforeAll(() => {
  const out = join(E2E_STORES_DIR, NAME);
  if (existsSync(join(out, 'zarr.json'))) return;
  const work = mkdtempSync(join(tmpdir(), 'record-e2e-'));
  execFileSync(join(root, '.venv-converter/bin/python'), [join(root, 'tests/fixtures/series-e2e.py'), work], { timeout: 60_000 });
  mkdirSync(E2E_STORES_DIR, { recursive: true });
  const tmp = join(work, NAME);
  execFileSync(
    process.execPath,
    [
      join(root, 'scripts/convert.mjs'),
      join(work, 'step_*_32x32x32_uint8.raw'),
      '--time',
      '--chunk',
      '16',
      '--rate',
      '8',
      '--out',
      tmp,
      '--quiet',
    ],
    { timeout: 120_000 },
  );
  rmSync(out, { recursive: true, force: true });
  renameSync(tmp, out);
  rmSync(work, { recursive: true, force: true });
});

interface Recording {
  active: boolean;
  from: number;
  to: number;
  recorded: number;
  toRecord: number;
  frames: number;
  mimeType: string | null;
  width: number;
  height: number;
  size: number | null;
  url: string | null;
  fileName: string | null;
  message: string | null;
}
interface Playback {
  index: number;
  playing: boolean;
  busy: boolean;
  recording: Recording | null;
}
type StoreWindow = { zfpisoStore?: { done: boolean; shownLevel: number | null; playback?: Playback } };
const playback = (page: Page) => page.evaluate(() => (window as unknown as StoreWindow).zfpisoStore?.playback) as Promise<Playback>;

async function settledAt(page: Page, t: number): Promise<void> {
  await page.waitForFunction(
    (t) => {
      const s = (window as unknown as StoreWindow).zfpisoStore;
      const p = s?.playback;
      return s?.done === true && s.shownLevel === 0 && p?.index === t && !p.busy && !p.playing;
    },
    t,
    { timeout: 60_000 },
  );
}

/** One EBML element: its ID (with its length marker), where its data starts and its size (null: unknown). */
interface Element {
  id: number;
  start: number;
  size: number | null;
}

function vint(b: Uint8Array, at: number, keepMarker: boolean): { value: number; length: number; unknown: boolean } {
  const first = b[at];
  let length = 1;
  while (length <= 8 && !(first & (0x80 >> (length - 1)))) length++;
  if (length > 8) throw new Error(`bad EBML length at ${at}`);
  let value = keepMarker ? first : first & (0xff >> length);
  let allOnes = value === 0xff >> length;
  for (let i = 1; i < length; i++) {
    value = value * 256 + b[at + i];
    if (b[at + i] !== 0xff) allOnes = false;
  }
  return { value, length, unknown: !keepMarker && allOnes };
}

function readElement(b: Uint8Array, at: number): Element {
  const id = vint(b, at, true);
  const size = vint(b, at + id.length, false);
  return { id: id.value, start: at + id.length + size.length, size: size.unknown ? null : size.value };
}

const uint = (b: Uint8Array, e: Element) => b.subarray(e.start, e.start + e.size!).reduce((v, x) => v * 256 + x, 0);
const text = (b: Uint8Array, e: Element) =>
  Buffer.from(b.subarray(e.start, e.start + e.size!))
    .toString('latin1')
    .replace(/\0+$/, '');

/** What a WebM holds, by a flat walk of its elements (masters entered, whatever their size: MediaRecorder writes live WebM, sizes unknown). */
function walkWebm(b: Uint8Array) {
  // Segment, SeekHead, Info, Tracks, TrackEntry, Video, Cluster, BlockGroup, Cues, Tags
  const masters = new Set([0x18538067, 0x114d9b74, 0x1549a966, 0x1654ae6b, 0xae, 0xe0, 0x1f43b675, 0xa0, 0x1c53bb6b, 0x1254c367]);
  const header = readElement(b, 0);
  if (header.id !== 0x1a45dfa3) throw new Error('no EBML header');
  let docType = '';
  for (let at = header.start; at < header.start + header.size!; ) {
    const e = readElement(b, at);
    if (e.id === 0x4282) docType = text(b, e);
    at = e.start + e.size!;
  }
  const out = {
    docType,
    codec: '',
    width: 0,
    height: 0,
    clusters: 0,
    blocks: [] as { track: number; time: number; key: boolean; data: number[] }[],
  };
  let clusterTime = 0;
  for (let at = header.start + header.size!; at < b.length; ) {
    const e = readElement(b, at);
    if (masters.has(e.id)) {
      if (e.id === 0x1f43b675) out.clusters++;
      at = e.start;
      continue;
    }
    if (e.size === null) throw new Error(`element ${e.id.toString(16)} of unknown size`);
    if (e.id === 0x86) out.codec = text(b, e);
    else if (e.id === 0xb0) out.width = uint(b, e);
    else if (e.id === 0xba) out.height = uint(b, e);
    else if (e.id === 0xe7) clusterTime = uint(b, e);
    else if (e.id === 0xa3 || e.id === 0xa1) {
      // (Simple)Block: track number, signed 16-bit time relative to the cluster, flags, the frame
      const track = vint(b, e.start, false);
      const p = e.start + track.length;
      const rel = (b[p] << 8) | b[p + 1];
      const flags = b[p + 2];
      if (flags & 0x06) throw new Error('laced blocks');
      out.blocks.push({
        track: track.value,
        time: clusterTime + (rel & 0x8000 ? rel - 0x10000 : rel),
        key: e.id === 0xa3 && (flags & 0x80) !== 0,
        data: [...b.subarray(p + 3, e.start + e.size)],
      });
    }
    at = e.start + e.size;
  }
  return out;
}

test('Record: a WebM of every time point, one frame each, at the canvas size; cancel; no recorder', async ({ page, browser }) => {
  test.setTimeout(150_000);
  const errors = watchErrors(page);
  await openApp(page, `/?store=/stores/${NAME}#iso=100`);
  await settledAt(page, 0);
  const canvas = await page.evaluate(() => {
    const c = document.getElementById('view') as HTMLCanvasElement;
    return { width: c.width, height: c.height };
  });
  const button = page.locator('#store-playback [data-play="record"]');
  const bar = page.locator('#store-playback [data-k="record-progress"]');
  const status = page.locator('#store-playback [data-k="record-status"]');
  const link = page.locator('#store-playback a[data-k="record-file"]');
  await expect(button).toHaveText('● record');
  await expect(bar).toBeHidden();

  // Record from t = 0: the progress bar counts the time points recorded
  const started = Date.now();
  await button.click();
  await expect(button).toHaveText('■ cancel');
  await expect(bar).toBeVisible();
  await expect(bar).toHaveAttribute('max', '6');
  await expect(status).toContainText(/recording: [0-6] of 6 time points/);
  await page.waitForFunction(() => (window as unknown as StoreWindow).zfpisoStore?.playback?.recording?.url != null, null, {
    timeout: 90_000,
  });
  const took = Date.now() - started;
  const p = await playback(page);
  const r = p.recording!;
  expect(r).toMatchObject({ active: false, from: 0, to: 5, recorded: 6, toRecord: 6, frames: 6, message: null });
  expect(r.fileName).toBe('record-e2e-t0-5.webm');
  expect(r.mimeType).toMatch(/^video\/webm/);
  expect([r.width, r.height]).toEqual([canvas.width & ~1, canvas.height & ~1]);
  expect(p.index).toBe(5);
  expect(p.playing).toBe(false);
  await expect(bar).toBeHidden();
  await expect(button).toHaveText('● record');
  await expect(link).toBeVisible();
  await expect(link).toHaveAttribute('download', 'record-e2e-t0-5.webm');
  await expect(link).toContainText('6 frames');
  expect(await link.getAttribute('href')).toBe(r.url);

  // the file, read through its blob URL in the page, walked here
  const bytes = new Uint8Array(await page.evaluate(async (url) => [...new Uint8Array(await (await fetch(url)).arrayBuffer())], r.url!));
  expect(bytes.length).toBe(r.size);
  expect([...bytes.subarray(0, 4)]).toEqual([0x1a, 0x45, 0xdf, 0xa3]);
  const webm = walkWebm(bytes);
  expect(webm.docType).toBe('webm');
  expect(webm.codec).toMatch(/^V_VP[89]$/);
  expect([webm.width, webm.height]).toEqual([r.width, r.height]);
  expect(webm.clusters).toBeGreaterThanOrEqual(1);
  expect(webm.blocks.length).toBe(6);
  expect(webm.blocks[0].key).toBe(true);
  const times = webm.blocks.map((b) => b.time);
  expect([...times].sort((a, b) => a - b)).toEqual(times);

  // every block decoded by the browser's own decoder: 6 frames at the canvas size, the ball growing
  const decoded = await page.evaluate(
    async ({ codec, blocks }) => {
      const frames: { width: number; height: number; area: number }[] = [];
      const pending: Promise<void>[] = [];
      let failed: string | null = null;
      const decoder = new VideoDecoder({
        output: (f) => {
          pending.push(
            (async () => {
              const c = new OffscreenCanvas(f.displayWidth, f.displayHeight);
              const g = c.getContext('2d')!;
              g.drawImage(f, 0, 0);
              const { width, height } = { width: f.displayWidth, height: f.displayHeight };
              f.close();
              const d = g.getImageData(0, 0, width, height).data;
              // pixels away from the corner's (background) colour: the surface's area on screen
              let area = 0;
              for (let i = 0; i < d.length; i += 4)
                if (Math.abs(d[i] - d[0]) + Math.abs(d[i + 1] - d[1]) + Math.abs(d[i + 2] - d[2]) > 48) area++;
              frames.push({ width, height, area });
            })(),
          );
        },
        error: (e) => {
          failed = e.message;
        },
      });
      decoder.configure({ codec: codec === 'V_VP8' ? 'vp8' : 'vp09.00.10.08' });
      for (const b of blocks)
        decoder.decode(new EncodedVideoChunk({ type: b.key ? 'key' : 'delta', timestamp: b.time * 1000, data: new Uint8Array(b.data) }));
      await decoder.flush();
      await Promise.all(pending);
      decoder.close();
      return { frames, failed };
    },
    { codec: webm.codec, blocks: webm.blocks },
  );
  expect(decoded.failed).toBeNull();
  expect(decoded.frames.length).toBe(6);
  for (const f of decoded.frames) expect([f.width, f.height]).toEqual([r.width, r.height]);
  const areas = decoded.frames.map((f) => f.area);
  expect(areas[0]).toBeGreaterThan(500);
  // the ball grows over the time points: each frame is its own time point, in order
  for (let i = 1; i < areas.length; i++) expect(areas[i]).toBeGreaterThan(areas[i - 1]);
  console.log(`record: 6 time points in ${took} ms, ${r.size} bytes, ${r.mimeType}, ${r.width}x${r.height}, areas ${areas.join(' ')}`);

  // cancel half way: nothing offered, playback stopped, the link of the last one gone
  await page.locator('#store-playback input[data-play="time"]').evaluate((el: HTMLInputElement) => {
    el.value = '1';
    el.dispatchEvent(new Event('change', { bubbles: true }));
  });
  await settledAt(page, 1);
  await button.click();
  await page.waitForFunction(() => ((window as unknown as StoreWindow).zfpisoStore?.playback?.recording?.recorded ?? 0) >= 2);
  await button.click();
  await page.waitForFunction(() => !(window as unknown as StoreWindow).zfpisoStore?.playback?.busy);
  const c = (await playback(page)).recording!;
  expect(c).toMatchObject({ active: false, from: 1, to: 5, url: null, size: null, message: 'Recording cancelled.' });
  expect(c.recorded).toBeLessThan(5);
  expect((await playback(page)).playing).toBe(false);
  await expect(status).toHaveText('Recording cancelled.');
  await expect(link).toBeHidden();
  await expect(bar).toBeHidden();
  expect(errors).toEqual([]);

  // a browser that cannot record says so
  const other = await browser.newPage();
  const otherErrors = watchErrors(other);
  await other.addInitScript(() => {
    delete (window as { MediaRecorder?: unknown }).MediaRecorder;
  });
  await openApp(other, `/?store=/stores/${NAME}#iso=100`);
  await settledAt(other, 0);
  await other.locator('#store-playback [data-play="record"]').click();
  await expect(other.locator('#store-playback [data-k="record-status"]')).toHaveText(
    'This browser cannot record a movie (no MediaRecorder).',
  );
  expect((await playback(other)).recording).toMatchObject({ active: false, recorded: 0, url: null });
  expect((await playback(other)).playing).toBe(false);
  await other.close();
  expect(otherErrors).toEqual([]);
});
