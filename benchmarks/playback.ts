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
// PREFETCH=MB[,MB...] (default 256): the next time point fetched while one
// is computed, within that many MiB of CPU memory (0: none), each a run.
// Inputs: by default a generated series (SERIES=NxT, default 128x8: a
// Gaussian ball moving along x over T time points, NumPy raw files converted
// with `convert 'step_*.raw' --time`, rate chosen from the data) in a
// temporary folder, removed at the end; STORES=path,path (folders or URLs
// of stores with a t axis) plays those instead. Environment:
// - SERIES=NxT: the generated series' edge and time points (the issue's
//   sizes: 256x20 and 1024x8);
// - DTYPE=float32|uint8: its raw input (default float32 below 512^3, as the
//   committed 128^3 results; uint8 from 512^3: the field times 255, rounded,
//   1 GiB a time point at 1024^3 instead of 4; the store is float32 zfp
//   either way, at the rate chosen from that input);
// - RATE: the converter's --rate instead of the rate chosen from the data;
// - KEEP=path.zarr: the generated store is kept there and reused by a later
//   run with the same SERIES (a complete store there of another shape is
//   refused); a conversion that failed or was interrupted leaves its raw
//   input in path.zarr.raw/ and the next run resumes it. Generation and
//   conversion seconds go into the JSON's `series` when this run made it;
// - BUDGET_MB (default 256), ISO (default ISO_FRACTION=0.5 of the store's
//   value range), TIME (a start:stop[:step] slice, default all),
//   LINKS=localhost,link, REPEATS (default 4, at least 2: the first is
//   discarded), JSON (default benchmarks/results/playback-swiftshader.json:
//   give another path for trial runs).
// Running the issue's sizes (times, disk, what SwiftShader manages):
// benchmarks/README.md.
import { execFileSync } from 'node:child_process';
import { existsSync, mkdirSync, mkdtempSync, readFileSync, rmSync, statSync } from 'node:fs';
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
import { SeriesPrefetch } from '../src/store/series/prefetch.ts';
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
/** PREFETCH=MB[,MB...]: CPU bytes the next time point may take when fetched ahead, each a run of its own (0: none; default 256). */
const prefetchMbs = (env.PREFETCH ?? '256').split(',').map(Number);
if (prefetchMbs.some((m) => !(m >= 0))) throw new Error(`PREFETCH=${env.PREFETCH}: MB, 0 or more`);
const links = (env.LINKS ?? 'localhost,link').split(',').map((l) => (l === 'link' ? linkName : 'localhost'));
const jsonOut = env.JSON ?? join(root, 'benchmarks/results/playback-swiftshader.json');
const [seriesN, seriesT] = (env.SERIES ?? '128x8').split('x').map(Number);
// float32 below 512^3 (the committed 128^3 results' input), uint8 from there (a quarter of the bytes)
const seriesDtype = env.DTYPE ?? (seriesN >= 512 ? 'uint8' : 'float32');

/** What SERIES / KEEP made: the store and, when it was made by this run, how long that took. */
interface Generated {
  store: string;
  dtype: string;
  /** Reused from KEEP (complete, the same size and time points): nothing was generated. */
  reused: boolean;
  /** A conversion a previous run left unfinished, resumed from its raw files (kept under KEEP). */
  resumed?: boolean;
  /** Writing the raw input with NumPy, s. */
  writeSeconds?: number;
  /** `convert 'step_*.raw' --time`, s. */
  convertSeconds?: number;
  rawBytes?: number;
}

/** The converter's attributes of the store at `path` (zarr.json's zfpzarr), or null where there is none. */
function storeAttributes(path: string): { complete?: boolean; params?: { shape?: number[]; source_dtype?: string } } | null {
  if (!existsSync(join(path, 'zarr.json'))) return null;
  return JSON.parse(readFileSync(join(path, 'zarr.json'), 'utf8')).attributes?.zfpzarr ?? null;
}

const rawName = (i: number, n: number, dtype: string) => `step_${String(i).padStart(3, '0')}_${n}x${n}x${n}_${dtype}.raw`;

/**
 * A moving ball, SERIES=NxT: step_TTT_NxNxN_DTYPE.raw written by NumPy (z
 * slabs of at most 16M voxels, so a 1024^3 time point never sits in memory
 * whole) in OUT.raw/, converted to one store with a t axis at `out`.
 * float32: exp(-d^2/r^2), r = N/6; uint8: the same field times 255,
 * rounded (a quarter of the bytes: 1 GiB a time point at 1024^3). The
 * converter reads either and writes float32 zfp chunks. The raw files are
 * removed once the store is complete; under KEEP a failed or interrupted
 * conversion leaves them, and the next run converts them again, which
 * resumes the store (`resume`: they are there, so they are not rewritten:
 * the converter knows its input by path, size and mtime).
 */
function generateSeries(out: string, n: number, t: number, dtype: string, resume = false): Generated {
  const dir = `${out}.raw`;
  const rawBytes = n ** 3 * t * (dtype === 'uint8' ? 1 : 4);
  let converted = false;
  try {
    const t0 = performance.now();
    if (!resume) {
      mkdirSync(dir, { recursive: true });
      console.log(`writing a ${n}^3 x ${t} series (moving ball, ${dtype}, ${(rawBytes / 2 ** 30).toFixed(2)} GiB of raw input) in ${dir}`);
      runPython(
        `
import sys, numpy as np
d, n, T, dtype = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
ax = np.arange(n, dtype=np.float32)
r = n / 6
slab = max(1, (1 << 24) // (n * n))
for t in range(T):
    cx = n * (0.3 + 0.4 * t / max(T - 1, 1))
    with open(f'{d}/step_{t:03d}_{n}x{n}x{n}_{dtype}.raw', 'wb') as f:
        for z0 in range(0, n, slab):
            z, y, x = np.meshgrid(ax[z0:z0 + slab], ax, ax, indexing='ij')
            v = np.exp(-((x - cx) ** 2 + (y - n / 2) ** 2 + (z - n / 2) ** 2) / (r * r)).astype(np.float32)
            if dtype == 'uint8':
                v = np.rint(v * 255).astype(np.uint8)
            v.tofile(f)
`,
        [dir, String(n), String(t), dtype],
        3_600_000,
      );
      console.log(`  written in ${((performance.now() - t0) / 1000).toFixed(1)} s`);
    } else console.log(`resuming the conversion of ${dir} into ${out}`);
    const t1 = performance.now();
    console.log(`converting to ${out}${env.RATE ? ` at rate ${env.RATE}` : ', rate chosen from the data'}`);
    execFileSync(
      process.execPath,
      [
        join(root, 'scripts/convert.mjs'),
        join(dir, `step_*_${n}x${n}x${n}_${dtype}.raw`),
        '--time',
        '--out',
        out,
        ...(env.RATE ? ['--rate', env.RATE] : []),
        ...(n >= 512 ? [] : ['--quiet']),
      ],
      { stdio: 'inherit' },
    );
    converted = true;
    const t2 = performance.now();
    console.log(`  converted in ${((t2 - t1) / 1000).toFixed(1)} s`);
    return {
      store: out,
      dtype,
      reused: false,
      ...(resume ? { resumed: true } : { writeSeconds: (t1 - t0) / 1000 }),
      convertSeconds: (t2 - t1) / 1000,
      rawBytes,
    };
  } finally {
    if (converted || !env.KEEP) rmSync(dir, { recursive: true, force: true });
  }
}

/**
 * SERIES in KEEP: reused when KEEP holds it complete, its conversion resumed
 * when a run left it incomplete with its raw files, else generated there;
 * without KEEP, generated in a temporary folder.
 */
function seriesStore(n: number, t: number, dtype: string, temp: () => string): Generated {
  if (dtype !== 'float32' && dtype !== 'uint8') throw new Error(`DTYPE=${dtype}: float32 or uint8`);
  if (!env.KEEP) return generateSeries(join(temp(), 'series.zarr'), n, t, dtype);
  const keep = resolve(env.KEEP);
  const attrs = storeAttributes(keep);
  const shape = attrs?.params?.shape ?? [];
  if (attrs && shape.join('x') !== [t, n, n, n].join('x'))
    throw new Error(`KEEP=${keep} holds a ${shape.join('x')} (t, z, y, x) store, not SERIES=${n}x${t}: remove it or name another`);
  if (attrs?.complete) {
    console.log(`reusing ${keep} (${n}^3 x ${t}, complete)`);
    return { store: keep, dtype: attrs.params?.source_dtype ?? '?', reused: true };
  }
  if (attrs || existsSync(keep)) {
    const raw = [...Array(t).keys()].map((i) => join(`${keep}.raw`, rawName(i, n, dtype)));
    if (raw.every((f) => existsSync(f) && statSync(f).size === n ** 3 * (dtype === 'uint8' ? 1 : 4)))
      return generateSeries(keep, n, t, dtype, true);
    throw new Error(`KEEP=${keep} is an unfinished store whose raw ${dtype} input (${keep}.raw/) is gone: remove it, then run again`);
  }
  return generateSeries(keep, n, t, dtype);
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

/**
 * One playback of `url` at `iso`: extractSeries' loop, timed, with the next
 * time point fetched ahead while one is computed (series/prefetch.ts) within
 * `prefetchBytes` (0: none), as `extract --time --prefetch MB` does.
 */
async function play(device: GpuContext, url: string, iso: number, times: number[] | null, prefetchBytes: number): Promise<Run> {
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
  const source = storeForLocation(url);
  const prefetch = new SeriesPrefetch();
  try {
    for (const [i, t] of indices.entries()) {
      const opened = performance.now();
      const prepared = await prefetch.take(t, source);
      const volume = await openInputSurface(quiet, gpu, url, {
        budget: budgetBytes,
        rate: seriesRate,
        time: t,
        prepared: prepared ?? undefined,
      });
      try {
        if (seriesRate === undefined && volume.store?.().source) seriesRate = volume.rate;
        rate = volume.rate;
        const next = indices[i + 1];
        const ahead = volume.ahead;
        if (next !== undefined && ahead && prefetchBytes > 0)
          prefetch.start(source, {
            time: next,
            open: (metered) => openStore(metered, url, { rate: seriesRate, time: next }),
            wanted: async (needsAt) => {
              await ahead.planned;
              return ahead.wanted(needsAt);
            },
            levels: ahead.levels,
            capacityBytes: prefetchBytes,
          });
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
  } finally {
    prefetch.cancel();
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
  let generated: Generated | undefined;
  const slice = env.TIME ? parseTimeSlice(env.TIME) : null;
  if (typeof slice === 'string') throw new Error(`TIME=${env.TIME}: ${slice}`);
  const rows: (string | number)[][] = [];
  const records: Record<string, unknown>[] = [];
  const servers: Server[] = [];
  try {
    if (env.STORES) stores = env.STORES.split(',').map((s) => (isStoreUrl(s) ? s : resolve(s)));
    else {
      generated = seriesStore(seriesN, seriesT, seriesDtype, () => {
        temp = mkdtempSync(join(tmpdir(), 'bench-playback-'));
        return temp;
      });
      stores = [generated.store];
    }
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
      for (const prefetchMb of prefetchMbs)
        for (const link of links) {
          let url = base;
          if (link !== 'localhost') {
            const proxy = linkProxy(new URL(base).origin);
            servers.push(proxy);
            url = `http://127.0.0.1:${await listen(proxy)}${new URL(base).pathname}`;
          }
          const runs: Run[] = [];
          for (let r = 0; r < repeats; r++) {
            const run = await play(device, url, iso, times, prefetchMb * 2 ** 20);
            console.log(
              `${basename(store)}, ${link}, prefetch ${prefetchMb} MiB, run ${r + 1}/${repeats}${r === 0 ? ' (discarded)' : ''}: first frame ${run.firstFrameMs.toFixed(0)} ms, ${run.timePointsPerSecond.toFixed(2)} time points/s after, ${(median(run.bytesFetched) / 2 ** 20).toFixed(2)} MiB per time point, GPU peak ${(run.gpuPeakBytes / 2 ** 20).toFixed(1)} MiB`,
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
            prefetchMb,
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
            prefetchBytes: prefetchMb * 2 ** 20,
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
    `bench:playback, ${adapter}, median of ${repeats - 1} after a discarded first; each time point opened and its level-0 surface computed in turn, the next fetched meanwhile within the prefetch bound (extract --time); budget ${budgetBytes / 2 ** 20} MiB; ${generated ? `a ${seriesN}^3 x ${seriesT} moving ball (${generated.dtype} input${generated.reused ? `, kept in ${generated.store}` : ''})` : 'STORES'}`,
    [
      'store',
      'level 0 x time points',
      'link',
      'prefetch MiB',
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
    series: generated
      ? {
          size: seriesN,
          timePoints: seriesT,
          field: `Gaussian ball exp(-d^2/(n/6)^2) moving along x, ${generated.dtype === 'uint8' ? 'times 255 rounded to uint8' : generated.dtype}`,
          ...(env.KEEP ? { kept: generated.store } : {}),
          reused: generated.reused,
          ...(generated.reused
            ? {}
            : {
                rawBytes: generated.rawBytes,
                ...(generated.resumed ? { resumed: true } : { writeSeconds: generated.writeSeconds }),
                convertSeconds: generated.convertSeconds,
              }),
        }
      : null,
    link: LINK,
    repeats,
    budgetBytes,
    isoFraction: env.ISO !== undefined ? null : isoFraction,
    records,
  });
  device.device.destroy();
}

await main();
