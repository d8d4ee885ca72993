// Scrubbing, instrumented from outside the app: an init script wraps
// GPUQueue.submit (command buffers tagged with their encoder's label),
// GPUBuffer.mapAsync (request and resolution) and, only to timestamp the
// frame's completion, onSubmittedWorkDone after each frame's submit. The
// page then gets isovalues through the slider's input event.
//  - each computed surface's first frame is submitted after its compute and
//    before its statistics are mapped (the frame does not wait for them);
//  - while scrubbing, computations are submitted while an earlier one's
//    statistics map is still pending (no serialization through a readback).
// It also prints what it measured (input -> first frame whose GPU work is
// done after the compute; surfaces per second while scrubbing), the figures
// quoted in src/isosurface/README.md.
import { expect, test, type Page } from '@playwright/test';
import { openApp } from './page.ts';
import { SHARED_VOLUMES } from './volume-page.ts';

interface TraceEvent {
  k: 'input' | 'submit' | 'done' | 'map' | 'mapped';
  t: number;
  label?: string;
  iso?: number;
  /** For 'done': the submit time of the frame it completes. */
  of?: number;
}

declare global {
  interface Window {
    __trace: TraceEvent[];
  }
}

function instrument(): void {
  const trace: TraceEvent[] = [];
  window.__trace = trace;
  type Tagged = { __label?: string };
  const create = GPUDevice.prototype.createCommandEncoder;
  GPUDevice.prototype.createCommandEncoder = function (this: GPUDevice, d?: GPUCommandEncoderDescriptor) {
    const e = create.call(this, d) as GPUCommandEncoder & Tagged;
    e.__label = d?.label ?? '';
    return e;
  };
  const finish = GPUCommandEncoder.prototype.finish;
  GPUCommandEncoder.prototype.finish = function (this: GPUCommandEncoder & Tagged, d?: GPUCommandBufferDescriptor) {
    const b = finish.call(this, d) as GPUCommandBuffer & Tagged;
    b.__label = this.__label;
    return b;
  };
  const submit = GPUQueue.prototype.submit;
  GPUQueue.prototype.submit = function (this: GPUQueue, buffers: Iterable<GPUCommandBuffer>) {
    const list = [...buffers] as (GPUCommandBuffer & Tagged)[];
    const t = performance.now();
    for (const b of list) trace.push({ k: 'submit', t, label: b.__label });
    const r = submit.call(this, list);
    if (list.some((b) => b.__label === 'Viewer.frame'))
      void this.onSubmittedWorkDone().then(() => trace.push({ k: 'done', t: performance.now(), of: t }));
    return r;
  };
  const mapAsync = GPUBuffer.prototype.mapAsync;
  GPUBuffer.prototype.mapAsync = function (this: GPUBuffer, ...a: Parameters<GPUBuffer['mapAsync']>) {
    const label = this.label;
    trace.push({ k: 'map', t: performance.now(), label });
    return mapAsync.apply(this, a).then((v) => {
      trace.push({ k: 'mapped', t: performance.now(), label });
      return v;
    });
  };
}

const VOLUME = `${SHARED_VOLUMES}bonsai_256x256x256_float32.rate4.zfp`;
const isCompute = (e: TraceEvent) => e.k === 'submit' && e.label === 'Isosurface.compute';
const isStats = (e: TraceEvent) => e.label?.startsWith('Isosurface.stats') ?? false;

/** Sets the slider to fraction f of its range and fires its input event (logged). */
async function input(page: Page, fractions: number[], gapMs: number): Promise<void> {
  await page.evaluate(
    async ({ fractions, gapMs }) => {
      const slider = document.getElementById('iso-slider') as HTMLInputElement;
      const lo = Number(slider.min);
      const hi = Number(slider.max);
      for (const f of fractions) {
        slider.value = String(Math.round(lo + f * (hi - lo)));
        window.__trace.push({ k: 'input', t: performance.now(), iso: f });
        slider.dispatchEvent(new Event('input', { bubbles: true }));
        if (gapMs > 0) await new Promise((r) => setTimeout(r, gapMs));
      }
    },
    { fractions, gapMs },
  );
}

async function settle(page: Page): Promise<void> {
  await page.waitForFunction(
    () => window.zfpiso!.stats !== undefined && Math.fround(window.zfpiso!.stats.isovalue) === Math.fround(window.zfpiso!.iso!),
    null,
    { timeout: 120_000 },
  );
  // every map requested so far resolved, and a frame after the last compute done
  await page.waitForFunction(
    () => {
      const tr = window.__trace;
      const maps = tr.filter((e) => e.k === 'map' && e.label?.startsWith('Isosurface.stats')).length;
      const mapped = tr.filter((e) => e.k === 'mapped' && e.label?.startsWith('Isosurface.stats')).length;
      const lastCompute = tr.filter((e) => e.k === 'submit' && e.label === 'Isosurface.compute').pop()?.t ?? 0;
      return maps === mapped && tr.some((e) => e.k === 'done' && (e.of ?? 0) > lastCompute);
    },
    null,
    { timeout: 120_000 },
  );
}

const median = (xs: number[]) => {
  const s = [...xs].sort((a, b) => a - b);
  return s.length ? s[Math.floor((s.length - 1) / 2)] : NaN;
};

test('scrubbing: each surface is drawn before its statistics are mapped, and surfaces are submitted without waiting for maps', async ({
  page,
}) => {
  test.setTimeout(400_000);
  await page.addInitScript(instrument);
  await openApp(page, `/?url=${VOLUME}`);
  await settle(page);

  // 1. Isolated inputs: input -> first frame submitted after the compute -> its GPU work done.
  const isolated = [0.32, 0.5, 0.36, 0.55, 0.4, 0.6];
  const latencies: number[] = [];
  const mapLatencies: number[] = [];
  for (const f of isolated) {
    const from = await page.evaluate(() => window.__trace.length);
    await input(page, [f], 0);
    await settle(page);
    const tr = (await page.evaluate(() => window.__trace)).slice(from);
    const inputAt = tr.find((e) => e.k === 'input')!.t;
    const computes = tr.filter(isCompute);
    expect(computes.length).toBeGreaterThan(0);
    const lastCompute = computes[computes.length - 1].t;
    const frame = tr.find((e) => e.k === 'submit' && e.label === 'Viewer.frame' && e.t > lastCompute)!;
    const done = tr.find((e) => e.k === 'done' && e.of === frame.t)!;
    latencies.push(done.t - inputAt);
    const mapped = tr.filter((e) => e.k === 'mapped' && isStats(e)).pop()!;
    mapLatencies.push(mapped.t - inputAt);
  }

  // 2. Scrubbing: 24 inputs 30 ms apart.
  const from = await page.evaluate(() => window.__trace.length);
  const statsBefore = await page.evaluate(() => window.zfpiso!.statsCount);
  const scrub = Array.from({ length: 24 }, (_, i) => 0.3 + 0.3 * Math.abs(Math.sin(i / 3)));
  await input(page, scrub, 30);
  await settle(page);
  const statsAfter = await page.evaluate(() => window.zfpiso!.statsCount);
  const tr = (await page.evaluate(() => window.__trace)).slice(from);
  const firstInput = tr.find((e) => e.k === 'input')!.t;
  const lastMapped = tr.filter((e) => e.k === 'mapped' && isStats(e)).pop()!.t;
  const computes = tr.filter(isCompute);
  const surfaces = statsAfter - statsBefore;
  // Pair each compute submission with its statistics map (requested in submission order).
  const maps = tr.filter((e) => e.k === 'map' && isStats(e));
  const mappedAll = tr.filter((e) => e.k === 'mapped' && isStats(e));
  expect(maps.length).toBe(computes.length);
  let drawnBeforeStats = 0;
  let submittedWhileMapPending = 0;
  for (let i = 0; i < computes.length; i++) {
    const at = computes[i].t;
    const statsAt = mappedAll[i].t;
    if (tr.some((e) => e.k === 'submit' && e.label === 'Viewer.frame' && e.t > at && e.t < statsAt)) drawnBeforeStats++;
    if (i > 0 && mappedAll[i - 1].t > at) submittedWhileMapPending++;
  }
  const seconds = (lastMapped - firstInput) / 1000;
  console.log(
    `[scrub-pipeline] ${VOLUME.split('/').pop()}: input -> first frame done after the compute: median ${median(latencies).toFixed(0)} ms ` +
      `(${latencies.map((x) => x.toFixed(0)).join(', ')}); input -> statistics mapped: median ${median(mapLatencies).toFixed(0)} ms; ` +
      `scrubbing ${scrub.length} inputs 30 ms apart: ${computes.length} compute submissions, ${surfaces} surfaces in ${seconds.toFixed(2)} s = ` +
      `${(surfaces / seconds).toFixed(2)} surfaces/s; ${submittedWhileMapPending} submitted while the previous map was pending; ` +
      `${drawnBeforeStats}/${computes.length} drawn before their statistics were mapped`,
  );
  expect(drawnBeforeStats).toBe(computes.length);
  expect(submittedWhileMapPending).toBeGreaterThan(0);
});

test('frame time at ~2.4 M triangles (bonsai at iso 20.37): printed', async ({ page }) => {
  test.setTimeout(300_000);
  await page.addInitScript(instrument);
  await openApp(page, `/?url=${VOLUME}#iso=20.37`);
  await settle(page);
  const triangles = await page.evaluate(() => window.zfpiso!.stats!.triangles);
  const frames: number[] = [];
  const box = (await page.locator('#view').boundingBox())!;
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  for (let i = 0; i < 6; i++) {
    const from = await page.evaluate(() => window.__trace.length);
    await page.mouse.wheel(0, i % 2 ? 40 : -40);
    await page.waitForFunction((n) => window.__trace.slice(n).some((e) => e.k === 'done'), from, { timeout: 60_000 });
    const tr = (await page.evaluate(() => window.__trace)).slice(from);
    const done = tr.find((e) => e.k === 'done')!;
    frames.push(done.t - done.of!);
    // let any frame requested meanwhile finish before the next one
    await page.waitForTimeout(200);
    await page.waitForFunction(() => {
      const tr = window.__trace;
      const frames = tr.filter((e) => e.k === 'submit' && e.label === 'Viewer.frame').length;
      return tr.filter((e) => e.k === 'done').length >= frames;
    });
  }
  const kept = frames.slice(1);
  console.log(
    `[frame-time] ${VOLUME.split('/').pop()} iso 20.37, ${triangles} triangles: frame submit -> GPU done median ${median(kept).toFixed(0)} ms (${kept.map((x) => x.toFixed(0)).join(', ')})`,
  );
  expect(triangles).toBeGreaterThan(2e6);
});
