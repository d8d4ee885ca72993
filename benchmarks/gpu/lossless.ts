// bench:gpu's published-style store (issue 37): an N^3 uint8 volume with
// structure in a ball and empty space around it, written by zarr-python the
// way public collections are (Zarr v3, OME 0.5, zstd, 64^3 chunks in shards,
// a 2x2x2-mean pyramid down to one chunk, no range arrays), made on the
// machine that runs the benchmark, served over HTTP on localhost and through
// the simulated 100 Mbit/s link. Refined by the view (the page's Fit of the
// volume, then a zoom onto the ball's edge) within the budget, as the page
// streams it; the bricks are zfp-encoded on the GPU as they arrive and their
// ranges learnt then (src/store/learnt-ranges.ts). Measured per link:
// - open (metadata) and the coarsest level read whole for the value range;
// - the first isovalue: time to the first update and to the whole cut, bytes
//   fetched;
// - a second isovalue: bytes fetched and bricks put (the learnt ranges skip
//   the bricks that hold none of it), time to the whole cut;
// - the zoom: time to the whole cut, level-0 bricks on screen, GPU peak;
// - the CPU side of a brick on one thread (fetch, zstd, assemble, pad; the
//   page runs it in up to 4 Web Workers, Node has none), bricks read one
//   after the other.
import { execFileSync } from 'node:child_process';
import { existsSync } from 'node:fs';
import { join } from 'node:path';
import type { Isosurface } from '../../src/isosurface/isosurface.ts';
import type { IsosurfaceStats } from '../../src/isosurface/types.ts';
import { ChunkFetcher } from '../../src/store/fetch/chunk-fetcher.ts';
import { chunkedGpu, storeEncoder } from '../../src/store/gpu-port.ts';
import { readLevelValues } from '../../src/store/level-values.ts';
import { cameraForBox, cameraFromView, fitBox0, sceneRadiusOf } from '../../src/store/view/camera.ts';
import { DEFAULT_VIEWPORT } from '../../src/store/view/view-request.ts';
import { DEFAULT_TOLERANCE_PX, StoreStream } from '../../src/store/stream/store-stream.ts';
import { openStore } from '../../src/store/zarr/open-store.ts';
import type { ChunkedVolume } from '../../src/zfp/chunked-volume.ts';
import { linkStore } from '../stream-scale.ts';
import type { BenchRun } from './context.ts';
import { serveStores } from './serve.ts';
// the store's writer, shared with the page tests (zarr-python: N^3 uint8 ball, zstd, 64^3 chunks in shards, mean pyramid)
import MAKE_STORE from '../../tests/fixtures/ball-store.py?raw';

const SECTION = 'lossless';
const ISO = [100.5, 200.5];
const MiB = 2 ** 20;

function makeStore(run: BenchRun, edge: number): { name: string; seconds: number } {
  const name = `ball${edge}-zstd.zarr`;
  const out = join(run.paths.work, name);
  if (existsSync(join(out, 'zarr.json'))) return { name, seconds: 0 };
  const t0 = performance.now();
  console.log(`  writing ${name} (uint8, zstd, 64^3 chunks in shards, mean pyramid) with zarr-python...`);
  execFileSync(run.paths.python, ['-c', MAKE_STORE, String(edge), out], { stdio: 'inherit', timeout: 600_000 });
  return { name, seconds: (performance.now() - t0) / 1000 };
}

interface LinkRecord {
  link: string;
  openMs: number;
  coarseReadMs: number;
  valueRange: [number, number] | null;
  first: { firstUpdateMs: number; wholeMs: number; bytes: number; bricks: number };
  second: { wholeMs: number; bytes: number; bricks: number };
  zoom: { wholeMs: number; level0Bricks: number; bytes: number };
  gpuPeakBytes: number;
  learntBricks: number;
  /** Bricks handed over for the second isovalue although the learnt ranges excluded them (0 expected). */
  excluded: number;
  stops: string[];
}

export async function losslessSection(run: BenchRun): Promise<unknown> {
  const edge = run.plan.storeEdge;
  const budget = 2 * run.plan.storeBudgetBytes;
  const { name, seconds } = makeStore(run, edge);
  if (seconds > 0) console.log(`  written in ${seconds.toFixed(1)} s`);
  const server = await serveStores(run.paths.work);
  const url = `${server.base}/${name}`;
  const records: LinkRecord[] = [];
  try {
    // localhost twice (the first compiles the pipelines), then the link
    for (const link of ['localhost', 'localhost', 'link']) {
      const metered = linkStore(url, link);
      const t0 = performance.now();
      const store = await openStore(metered, url, { rate: 8 });
      const openMs = performance.now() - t0;
      const coarse = await readLevelValues(store, store.levels.length - 1);
      const coarseReadMs = performance.now() - t0 - openMs;
      const port = chunkedGpu(run.gpu, undefined, await storeEncoder(run.gpu, store));
      const fetcher = new ChunkFetcher(store);
      let put = 0;
      let excluded = 0;
      let secondIso = false;
      fetcher.onChunk((L, c) => {
        put++;
        // a brick handed over for the second isovalue that the ranges learnt so far exclude (its own is learnt after it arrives)
        if (secondIso && !stream.learnt.needs(L, ISO[1], c) && !store.levels[L].rangesPath) excluded++;
      });
      const stream = await StoreStream.byView<ChunkedVolume, IsosurfaceStats, Isosurface>(store, fetcher, port, budget);
      const stops: string[] = [];
      stream.onProgress((p) => {
        if (p.phase === 'stopped') stops.push(p.reason ?? 'stopped');
      });
      const box0 = fitBox0(store.levels[0].layout, 0);
      const sceneRadius = sceneRadiusOf(box0, store.voxelSize);
      const view = (box: typeof box0) => ({
        camera: cameraFromView(cameraForBox(box, store.voxelSize, DEFAULT_VIEWPORT).state, DEFAULT_VIEWPORT, sceneRadius),
        tolerancePx: DEFAULT_TOLERANCE_PX,
      });
      /** One refinement: ms to the first step shown and to the whole cut, bytes and bricks it fetched. */
      const measure = async (go: () => Promise<void>) => {
        const b0 = metered.meter.bytes;
        const p0 = put;
        const s0 = performance.now();
        let firstUpdate = Number.NaN;
        const off = stream.onShown(() => {
          if (Number.isNaN(firstUpdate)) firstUpdate = performance.now() - s0;
        });
        await go();
        off();
        const wholeMs = performance.now() - s0;
        await stream.learnSettled();
        return { firstUpdateMs: firstUpdate, wholeMs, bytes: metered.meter.bytes - b0, bricks: put - p0 };
      };
      await stream.setView(view(box0));
      const first = await measure(() => stream.setIsovalue(ISO[0]));
      secondIso = true;
      const second = await measure(() => stream.setIsovalue(ISO[1]));
      secondIso = false;
      // onto the ball's edge: a box an eighth of the volume wide where the ball meets empty space
      const e = edge / 8;
      const c = edge / 2 + 0.3 * edge * Math.SQRT1_2;
      const zoom = await measure(() => stream.setView(view([c - e, c - e, edge / 2 - e, c + e, c + e, edge / 2 + e])));
      records.push({
        link,
        openMs,
        coarseReadMs,
        valueRange: coarse?.valueRange ?? null,
        first,
        second: { wholeMs: second.wholeMs, bytes: second.bytes, bricks: second.bricks },
        zoom: {
          wholeMs: zoom.wholeMs,
          bytes: zoom.bytes,
          level0Bricks: stream.shown?.levels.find((l) => l.level === 0)?.drawn.length ?? 0,
        },
        gpuPeakBytes: port.meter.peak,
        learntBricks: store.levels.reduce((a, _, L) => a + stream.learnt.knownCount(L), 0),
        excluded,
        stops,
      });
      stream.destroy();
      store.close?.();
    }
    // the CPU side of a brick alone, one thread: bricks inside the ball read one after the other over localhost
    // (fetch, zstd, assemble, pad: what one of the page's decode workers does per brick)
    const store = await openStore(linkStore(url, 'localhost'), url, { rate: 8 });
    const lv0 = store.levels[0].layout;
    const g = lv0.chunkGrid;
    const centre = g.map((n) => Math.floor(n / 2));
    const sample: number[] = [];
    for (let k = 0; k < Math.min(32, g[0]) && sample.length < 32; k++) {
      const x = Math.min(g[0] - 1, centre[0] - 2 + (k % 4));
      const y = Math.min(g[1] - 1, centre[1] - 2 + (Math.floor(k / 4) % 4));
      const z = Math.min(g[2] - 1, centre[2] - 1 + Math.floor(k / 16));
      sample.push(Math.max(0, x) + g[0] * (Math.max(0, y) + g[1] * Math.max(0, z)));
    }
    const bricks = [...new Set(sample)];
    const d0 = performance.now();
    for (const c of bricks) await store.readChunk(0, c);
    const decodeSeconds = (performance.now() - d0) / 1000;
    store.close?.();
    const voxelsPerSecond = (bricks.length * lv0.chunkEdge ** 3) / decodeSeconds;
    run.figure(SECTION, `ball ${edge}^3 zstd: a brick's CPU side, one thread (M voxels/s)`, voxelsPerSecond / 1e6, 'M voxels/s');
    const measured = [records[1], records[2]];
    for (const r of measured) {
      const at = `ball ${edge}^3 zstd, ${r.link}`;
      run.figure(SECTION, `${at}: first update after the metadata (ms)`, r.first.firstUpdateMs, 'ms');
      run.figure(SECTION, `${at}: whole cut, first isovalue (ms)`, r.first.wholeMs, 'ms');
      run.figure(SECTION, `${at}: whole cut after the zoom (ms)`, r.zoom.wholeMs, 'ms');
      run.figure(SECTION, `${at}: first isovalue fetched (MiB)`, r.first.bytes / MiB, 'MiB');
      run.figure(SECTION, `${at}: second isovalue fetched (MiB)`, Math.max(r.second.bytes / MiB, 1e-6), 'MiB');
      run.check(
        SECTION,
        `${at}: GPU peak within the budget`,
        r.gpuPeakBytes <= budget,
        `${(r.gpuPeakBytes / MiB).toFixed(1)} of ${(budget / MiB).toFixed(0)} MiB`,
      );
      run.check(SECTION, `${at}: every refinement reached its whole cut`, r.stops.length === 0, r.stops.join('; ') || 'no stop');
      run.check(
        SECTION,
        `${at}: the second isovalue fetched no brick its learnt ranges exclude`,
        r.excluded === 0 && r.learntBricks > 0,
        `${r.excluded} excluded bricks fetched; ${r.learntBricks} brick ranges learnt`,
      );
    }
    run.table({
      title: `published-style store: ball ${edge}^3 uint8, zstd, 64^3 chunks in shards, budget ${(budget / MiB).toFixed(0)} MiB, rate 8, iso ${ISO.join(' then ')} (second localhost run and the 100 Mbit/s link)`,
      header: [
        'link',
        'open ms',
        'coarsest read ms',
        'first update ms',
        'whole cut ms',
        'fetched MiB',
        '2nd iso bricks',
        '2nd iso MiB',
        'zoom whole ms',
        'zoom level-0 bricks',
        'GPU peak MiB',
      ],
      rows: measured.map((r) => [
        r.link,
        r.openMs,
        r.coarseReadMs,
        r.first.firstUpdateMs,
        r.first.wholeMs,
        (r.first.bytes / MiB).toFixed(1),
        `${r.second.bricks} (1st: ${r.first.bricks})`,
        (r.second.bytes / MiB).toFixed(1),
        r.zoom.wholeMs,
        r.zoom.level0Bricks,
        (r.gpuPeakBytes / MiB).toFixed(1),
      ]),
    });
    run.notes.push(
      `lossless: a brick's CPU side (fetch over localhost, zstd, assemble, pad) read one after the other: ${(voxelsPerSecond / 1e6).toFixed(1)} M voxels/s on one thread (${bricks.length} bricks of ${lv0.chunkEdge}^3); the page spreads it over up to 4 Web Workers, Node runs it on its one thread while the stream waits`,
    );
    return { store: name, writeSeconds: seconds, budgetBytes: budget, iso: ISO, runs: records, cpuVoxelsPerSecond: voxelsPerSecond };
  } finally {
    server.close();
  }
}
