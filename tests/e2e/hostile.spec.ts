// Hostile files in the pages (issue 13, non-Wasm readers): a lying name, a
// gzip bomb, NaN/Inf volumes and SWC files that are not trees each get a
// message naming the file; what can be drawn is drawn; the next file opens.
import { gzipSync } from 'node:zlib';
import { expect, test } from '@playwright/test';
import { openApp, watchErrors } from './page.ts';
import { acceptVolumeForm, dropBytes, loads, pageState, waitForLoad, waitIdle } from './volume-page.ts';

const f32 = (a: Float32Array) => new Uint8Array(a.buffer);

/** A 16³ float32 sphere distance field (0 at the centre, ~13.9 at the corners). */
function sphere(): Float32Array {
  const out = new Float32Array(16 ** 3);
  for (let z = 0, i = 0; z < 16; z++)
    for (let y = 0; y < 16; y++) for (let x = 0; x < 16; x++, i++) out[i] = Math.hypot(x - 7.5, y - 7.5, z - 7.5);
  return out;
}

function nrrd(lines: string[], payload: Uint8Array): Uint8Array {
  const head = new TextEncoder().encode(['NRRD0004', ...lines, '', ''].join('\n'));
  const out = new Uint8Array(head.length + payload.length);
  out.set(head);
  out.set(payload, head.length);
  return out;
}

test('main page: lying names, gzip bombs and NaN volumes get messages; a file after a rejected one opens', async ({ page }) => {
  test.setTimeout(300_000);
  const errors = watchErrors(page);
  await openApp(page);
  const start = await pageState(page);
  const last = page.locator('#messages .message').last();

  await dropBytes(page, 'v_4x4x4_float32.raw.crate0.zfp', new Uint8Array(64));
  await waitIdle(page);
  await expect(last).toContainText('v_4x4x4_float32.raw.crate0.zfp: the rate in the file name (0) is not a positive number');

  const allNan = new Float32Array(16 ** 3).fill(NaN);
  await dropBytes(page, 'nan_16x16x16_float32.raw', f32(allNan));
  await acceptVolumeForm(page);
  await waitIdle(page);
  await expect(last).toContainText('nan_16x16x16_float32.raw: all 4096 values are NaN or infinite (4096 NaN)');
  expect((await pageState(page)).loads).toBe(start.loads);

  // A few NaN and Inf: opened, with a notice; the value range is the finite one.
  const v = sphere();
  v[0] = NaN;
  v[1] = Infinity;
  v[2] = -Infinity;
  let before = await loads(page);
  await dropBytes(page, 'some_16x16x16_float32.raw', f32(v));
  await acceptVolumeForm(page);
  await waitForLoad(page, before);
  await expect(page.locator('#messages .message[data-kind="info"]').last()).toContainText(
    'some_16x16x16_float32.raw: 3 of 4096 values are not finite (1 NaN, 1 +Inf, 1 -Inf)',
  );
  const s = await pageState(page);
  const [lo, hi] = s.volume!.valueRange;
  expect(lo).toBeGreaterThan(0.5);
  expect(hi).toBeLessThan(14);
  expect(s.stats!.triangles).toBeGreaterThan(0);

  // A gzip bomb (1 GiB of zeros in ~1 MB) under a 16³ header: only 4096 bytes are inflated.
  const zeros = gzipSync(new Uint8Array(64 << 20), { level: 9 });
  const bomb = new Uint8Array(zeros.length * 16);
  for (let i = 0; i < 16; i++) bomb.set(zeros, i * zeros.length);
  before = await loads(page);
  const t0 = Date.now();
  await dropBytes(page, 'bomb.nrrd', nrrd(['type: uchar', 'dimension: 3', 'sizes: 16 16 16', 'encoding: gzip'], bomb));
  await acceptVolumeForm(page);
  await waitForLoad(page, before);
  expect(Date.now() - t0).toBeLessThan(60_000);
  expect((await pageState(page)).volume).toMatchObject({ kind: 'nrrd', dims: [16, 16, 16], fileName: 'bomb.nrrd' });

  // Damaged gzip (refused while checking the file, before the form), then a good file.
  await dropBytes(
    page,
    'cut.nrrd',
    nrrd(['type: float', 'dimension: 3', 'sizes: 16 16 16', 'encoding: gzip'], gzipSync(f32(sphere())).subarray(0, 200)),
  );
  await waitIdle(page);
  await expect(last).toContainText('cut.nrrd: the gzip data is damaged');
  before = await loads(page);
  await dropBytes(page, 'good_16x16x16_float32.raw', f32(sphere()));
  await acceptVolumeForm(page);
  await waitForLoad(page, before);
  expect((await pageState(page)).volume).toMatchObject({ kind: 'raw', fileName: 'good_16x16x16_float32.raw' });
  expect(errors).toEqual([]);
});

test('neuron page: an SWC file that is not a tree is drawn as far as valid, with a message saying what was found', async ({ page }) => {
  await openApp(page, '/neuron.html?demo=0');
  const swc = [
    '1 1 0 0 0 2 -1',
    '2 3 5 0 0 1 1',
    '3 3 10 0 0 1 2',
    '4 3 0 5 0 1 6',
    '5 3 0 10 0 1 4',
    '6 3 0 15 0 1 5',
    '7 3 20 0 0 1 7',
    '8 3 0 0 9 1 99',
  ].join('\n');
  await page.setInputFiles('#file-input', { name: 'loops.swc', mimeType: 'text/plain', buffer: Buffer.from(swc) });
  await expect(page.locator('#messages .message')).toContainText(
    'loops.swc: 1 sample is its own parent (id 7); not linked; 1 parent cycle (3 samples, id 4, 6, 5); their links are not drawn; 1 sample names a parent that is not in the file (id 8); drawn unlinked.',
  );
  await page.waitForFunction(() => window.neuron!.traces.length === 1);
  expect(await page.evaluate(() => window.neuron!.traces)).toEqual([{ name: 'loops.swc', samples: 8, visible: true }]);
  await expect(page.locator('body')).toHaveAttribute('data-status', 'ready');
});
