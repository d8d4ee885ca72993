// `npm run bench:playback`: a store's time series played headless, the way
// `extract STORE --time 0:T --iso v` plays it (src/cli/commands/extract.ts,
// extractSeries): the t axis read (storeTimeAxis), then each time point in
// turn opened as its own store session (openInputSurface -> openStoreInput,
// level 0 streamed: the chunks the surface needs), its surface computed at
// the isovalue, and the session destroyed before the next opens; one GPU
// device for the whole series, everything made on it counted (meteredGpu).
// A frame is a time point's surface computed on the GPU (not read back:
// the page draws it where it is). Per store and link it reports:
// - first frame ms: from the start (the t axis read) to time point 0's surface;
// - time points / s: over the rest, (T - 1) / (the time from the first
//   frame to the last);
// - bytes fetched per time point: the median over the time points of the
//   session's bytes (chunks, metadata, range arrays), and the first's;
// - GPU peak: the meter's peak over the whole series (pools, cache,
//   vertices, scratch), against the budget.
// Links: localhost HTTP (the dev server's /stores/ middleware,
// scripts/vite-stores.ts, on 127.0.0.1) and a simulated 100 Mbit/s link
// with 20 ms per request: a proxy in front of that server holding each
// response back as SimulatedLinkStore (src/store/zarr/stores.ts) does, one
// shared pipe (here in the server, since openStoreInput opens the store by
// its URL as extract does). Median of REPEATS (default 4) after a
// discarded first (compilation, the disk cache).
// Inputs: by default a generated series (SERIES=NxT, default 128x8: a
// Gaussian ball of float32 moving along x over T time points, NumPy raw
// files converted with `convert 'step_*.raw' --time`, rate chosen from the
// data) in a temporary folder, removed at the end; STORES=path,path (folders
// or URLs of stores with a t axis) plays those instead. BUDGET_MB (default
// 256), ISO (default ISO_FRACTION=0.5 of the store's value range), TIME
// (a start:stop[:step] slice, default all), LINKS=localhost,link, JSON
// (default benchmarks/results/playback-swiftshader.json). The issue's
// 1024^3 x 8 series (SERIES=1024x8) takes ~32 GB of raw float32 input
// (4 GiB a time point) and its conversion; it is left to a machine with
// the disk.
import { execFileSync } from 'node:child_process';
import { mkdtempSync, rmSync } from 'node:fs';
import { createServer, type Server } from 'node:http';
import { tmpdir } from 'node:os';
import { basename, dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { storesMiddleware } from '../scripts/vite-stores.ts';
import { openInputSurface } from '../src/cli/input.ts';
import { formatTimeSlice, parseTimeSlice, sliceIndices } from '../src/cli/time-selection.ts';
import { describeAdapter } from '../src/gpu/device.ts';
import type { GpuContext } from '../src/gpu/device.ts';
import { meteredGpu } from '../src/gpu/memory-meter.ts';
import { requestNodeGpu } from '../src/gpu/node-gpu.ts';
import { storeTimeAxis } from '../src/store/cli-input.ts';
import { isStoreUrl, storeForLocation } from '../src/store/zarr/node-store.ts';
import { openStore } from '../src/store/zarr/open-store.ts';
import { runPython } from '../tests/helpers/python.ts';
import { printTable, summarize, writeJson } from './lib/report.ts';

const root = fileURLToPath(new URL('..', import.meta.url));
const env = process.env;
const repeats = Math.max(2, Number(env.REPEATS ?? 4));
const budgetBytes = Number(env.BUDGET_MB ?? 256) * 2 ** 20;
const isoFraction = Number(env.ISO_FRACTION ?? 0.5);
const LINK = { mbitPerSecond: 100, latencyMs: 20 };
const linkName = `${LINK.mbitPerSecond} Mbit/s + ${LINK.latencyMs} ms`;
const links = (env.LINKS ?? 'localhost,link').split(',').map((l) => (l === 'link' ? linkName : 'localhost'));
const jsonOut = env.JSON ?? join(root, 'benchmarks/results/playback-swiftshader.json');
const [seriesN, seriesT] = (env.SERIES ?? '128x8').split('x').map(Number);

/** A moving ball, SERIES=NxT: step_TTT_NxNxN_float32.raw written by NumPy, converted to one store with a t axis. */
function generateSeries(dir: string, n: number, t: number): string {
  console.log(`writing a ${n}^3 x ${t} series (moving ball, float32) in ${dir}`);
  runPython(
    `
import sys, numpy as np
d, n, T = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
ax = np.arange(n, dtype=np.float32)
z, y, x = np.meshgrid(ax, ax, ax, indexing='ij')
r = n / 6
for t in range(T):
    cx = n * (0.3 + 0.4 * t / max(T - 1, 1))
    d2 = (x - cx) ** 2 + (y - n / 2) ** 2 + (z - n / 2) ** 2
    np.exp(-d2 / (r * r)).astype(np.float32).tofile(f'{d}/step_{t:03d}_{n}x{n}x{n}_float32.raw')
`,
    [dir, String(n), String(t)],
    1_800_000,
  );
  const out = join(dir, 'series.zarr');
  execFileSync(
    process.execPath,
    [join(root, 'scripts/convert.mjs'), join(dir, `step_*_${n}x${n}x${n}_float32.raw`), '--time', '--out', out, '--quiet'],
    { stdio: 'inherit' },
  );
  for (let i = 0; i < t; i++) rmSync(join(dir, `step_${String(i).padStart(3, '0')}_${n}x${n}x${n}_float32.raw`));
  return out;
}

async function listen(server: Server): Promise<number> {
  await new Promise<void>((r) => server.listen(0, '127.0.0.1', () => r()));
  return (server.address() as { port: number }).port;
}

/** The dev server's /stores/ middleware over `folder`. */
function storesServer(folder: string): Server {
  const mw = storesMiddleware(folder);
  return createServer((req, res) =>
    mw(req, res, () => {
      res.statusCode = 404;
      res.end();
    }),
  );
}

/**
 * A simulated link in front of `upstream` (a URL prefix): each response is
 * fetched whole, then held back until a shared pipe of LINK.mbitPerSecond
 * has carried it, starting no sooner than LINK.latencyMs after the request
 * (SimulatedLinkStore's model, in the server).
 */
function linkProxy(upstream: string): Server {
  let pipeFreeAt = 0;
  const kept = ['content-type', 'content-range', 'accept-ranges', 'retry-after', 'access-control-allow-origin'];
  return createServer(async (req, res) => {
    const asked = performance.now();
    try {
      const headers: Record<string, string> = {};
      if (req.headers.range) headers.range = req.headers.range;
      const r = await fetch(upstream + (req.url ?? '/'), { method: req.method, headers });
      const body = new Uint8Array(await r.arrayBuffer());
      const start = Math.max(asked + LINK.latencyMs, pipeFreeAt);
      const end = start + (body.length * 8) / (LINK.mbitPerSecond * 1000);
      pipeFreeAt = end;
      await new Promise((w) => setTimeout(w, Math.max(0, end - performance.now())));
      res.statusCode = r.status;
      for (const h of kept) {
        const v = r.headers.get(h);
        if (v !== null) res.setHeader(h, v);
      }
      const length = r.headers.get('content-length');
      if (length !== null) res.setHeader('content-length', req.method === 'HEAD' ? length : String(body.length));
      res.end(req.method === 'HEAD' ? undefined : body);
    } catch (e) {
      res.statusCode = 502;
      res.end(String(e));
    }
  });
}

interface Run {
  firstFrameMs: number;
  /** Each time point, from its open to its surface (time point 0 without the t axis read). */
  frameMs: number[];
  restMs: number;
  timePointsPerSecond: number;
  bytesFetched: number[];
  requests: number[];
  triangles: number[];
  gpuPeakBytes: number;
  gpuBytesAfter: number;
  rate: number;
}

/** One playback of `url` at `iso`: extractSeries' loop, timed. */
async function play(device: GpuContext, url: string, iso: number, times: number[] | null): Promise<Run> {
  const { gpu, meter } = meteredGpu(device);
  const quiet = { log: () => {} };
  const t0 = performance.now();
  const axis = await storeTimeAxis(url, {});
  const indices = times ?? [...Array(axis?.count ?? 1).keys()];
  const frameMs: number[] = [],
    bytesFetched: number[] = [],
    requests: number[] = [],
    triangles: number[] = [];
  let firstFrameAt = NaN,
    rate = NaN,
    seriesRate: number | undefined;
  for (const t of indices) {
    const opened = performance.now();
    const volume = await openInputSurface(quiet, gpu, url, { budget: budgetBytes, rate: seriesRate, time: t });
    try {
      if (seriesRate === undefined && volume.store?.().source) seriesRate = volume.rate;
      rate = volume.rate;
      const stats = await volume.iso.compute(iso);
      const now = performance.now();
      if (Number.isNaN(firstFrameAt)) firstFrameAt = now;
      frameMs.push(now - opened);
      const record = volume.store!();
      bytesFetched.push(record.bytesFetched);
      requests.push(record.requests);
      triangles.push(stats.triangles);
    } finally {
      volume.destroy();
    }
  }
  const restMs = performance.now() - firstFrameAt;
  return {
    firstFrameMs: firstFrameAt - t0,
    frameMs,
    restMs,
    timePointsPerSecond: indices.length > 1 ? ((indices.length - 1) * 1000) / restMs : NaN,
    bytesFetched,
    requests,
    triangles,
    gpuPeakBytes: meter.peak,
    gpuBytesAfter: meter.bytes,
    rate,
  };
}

/** The median of all of `xs` (summarize drops the first by default: here the runs are dropped by `kept`). */
const median = (xs: number[]) => summarize(xs, false).median;
const stats = (xs: number[]) => summarize(xs, false);

async function main() {
  const device = await requestNodeGpu({ label: 'bench.playback' });
  let temp: string | undefined;
  let stores: string[];
  if (env.STORES) stores = env.STORES.split(',').map((s) => (isStoreUrl(s) ? s : resolve(s)));
  else {
    temp = mkdtempSync(join(tmpdir(), 'bench-playback-'));
    stores = [generateSeries(temp, seriesN, seriesT)];
  }
  const slice = env.TIME ? parseTimeSlice(env.TIME) : null;
  if (typeof slice === 'string') throw new Error(`TIME=${env.TIME}: ${slice}`);
  const rows: (string | number)[][] = [];
  const records: Record<string, unknown>[] = [];
  const servers: Server[] = [];
  try {
    for (const store of stores) {
      // a folder: served over localhost HTTP from its parent; a URL: as given
      let base: string;
      if (isStoreUrl(store)) base = store.replace(/\/$/, '');
      else {
        const s = storesServer(dirname(store));
        servers.push(s);
        base = `http://127.0.0.1:${await listen(s)}/stores/${basename(store)}`;
      }
      const meta = await openStore(storeForLocation(base), base);
      meta.close?.();
      const count = meta.time?.count ?? 1;
      const times = slice ? sliceIndices(slice, count) : null;
      const [lo, hi] = meta.valueRange ?? [0, 1];
      const iso = env.ISO !== undefined ? Number(env.ISO) : lo + isoFraction * (hi - lo);
      const lv0 = meta.levels[0].layout;
      for (const link of links) {
        let url = base;
        if (link !== 'localhost') {
          const proxy = linkProxy(new URL(base).origin);
          servers.push(proxy);
          url = `http://127.0.0.1:${await listen(proxy)}${new URL(base).pathname}`;
        }
        const runs: Run[] = [];
        for (let r = 0; r < repeats; r++) {
          const run = await play(device, url, iso, times);
          console.log(
            `${basename(store)}, ${link}, run ${r + 1}/${repeats}${r === 0 ? ' (discarded)' : ''}: first frame ${run.firstFrameMs.toFixed(0)} ms, ${run.timePointsPerSecond.toFixed(2)} time points/s after, ${(median(run.bytesFetched) / 2 ** 20).toFixed(2)} MiB per time point, GPU peak ${(run.gpuPeakBytes / 2 ** 20).toFixed(1)} MiB`,
          );
          runs.push(run);
        }
        const kept = runs.slice(1);
        const first = stats(kept.map((x) => x.firstFrameMs));
        const tps = stats(kept.map((x) => x.timePointsPerSecond));
        const bytes = median(kept.map((x) => median(x.bytesFetched)));
        const peak = Math.max(...kept.map((x) => x.gpuPeakBytes));
        const last = kept[kept.length - 1];
        const timePoints = last.frameMs.length;
        rows.push([
          basename(store),
          `${lv0.dims.join('x')} x ${timePoints}`,
          link,
          first.median,
          tps.median,
          median(kept.map((x) => median(x.frameMs))),
          (bytes / 2 ** 20).toFixed(2),
          (median(kept.map((x) => x.bytesFetched[0])) / 2 ** 20).toFixed(2),
          (peak / 2 ** 20).toFixed(1),
          median(last.triangles),
        ]);
        records.push({
          store: isStoreUrl(store) ? store : basename(store),
          link,
          dims: lv0.dims,
          chunkEdge: lv0.chunkEdge,
          levels: meta.levels.length,
          timePoints,
          timeCount: count,
          ...(slice ? { time: formatTimeSlice(slice) } : {}),
          iso,
          rate: last.rate,
          storeChunkBytes: meta.levels.reduce((a, l) => a + l.storedBytes, 0),
          firstFrameMs: first,
          timePointsPerSecond: tps,
          frameMsMedian: stats(kept.map((x) => median(x.frameMs))),
          bytesPerTimePointMedian: bytes,
          firstTimePointBytes: median(kept.map((x) => x.bytesFetched[0])),
          requestsPerTimePointMedian: median(kept.map((x) => median(x.requests))),
          gpuPeakBytes: peak,
          gpuBytesAfter: Math.max(...kept.map((x) => x.gpuBytesAfter)),
          budgetBytes,
          trianglesMedian: median(last.triangles),
          runs: kept,
        });
      }
    }
  } finally {
    for (const s of servers) {
      s.closeAllConnections();
      s.close();
    }
    if (temp) rmSync(temp, { recursive: true, force: true });
  }
  const adapter = describeAdapter(device.adapter);
  printTable(
    `bench:playback, ${adapter}, median of ${repeats - 1} after a discarded first; each time point opened and its level-0 surface computed in turn (extract --time); budget ${budgetBytes / 2 ** 20} MiB; ${stores.length === 1 && !env.STORES ? `a ${seriesN}^3 x ${seriesT} moving ball (float32)` : 'STORES'}`,
    [
      'store',
      'level 0 x time points',
      'link',
      'first frame ms',
      'time points/s',
      'ms per time point',
      'MiB / time point',
      'MiB first',
      'GPU peak MiB',
      'triangles',
    ],
    rows,
  );
  writeJson(jsonOut, {
    date: new Date().toISOString(),
    adapter,
    series: env.STORES ? null : { size: seriesN, timePoints: seriesT, field: 'Gaussian ball exp(-d^2/(n/6)^2) moving along x, float32' },
    link: LINK,
    repeats,
    budgetBytes,
    isoFraction: env.ISO !== undefined ? null : isoFraction,
    records,
  });
  device.device.destroy();
}

await main();
