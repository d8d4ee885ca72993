// `npm run bench:stream [-- --size N --repeats R --iso-fraction F --budget-mb M --only bonsai|gen --faults F --links localhost,link]`
// (`-- --codec zstd,blosc,gzip`: stores of lossless chunks, stream-codec.ts;
// `-- --flight [--size N]`: a fly-through refined by the view, stream-flight.ts):
// stores served over HTTP on localhost (the dev server's /stores/
// middleware) and through a simulated link (100 Mbit/s, 20 ms per request,
// in the fetch layer). The path is the store stream's planned level by level
// (the page's and the CLI's): the chunks the plan needs, fetched into
// ChunkedVolume pools, coarsest level first.
// - bonsai (256^3): time to the first surface (coarsest level) and to the
//   full-resolution one (level 0), bytes fetched / store size, level-0
//   chunks fetched against the plan's count, requests and retries, GPU bytes
//   held (counted where they are made) and their peak; next to the in-core
//   path (level 0 as one zfp stream read from disk). With --faults F every
//   case runs again through the server's faulty prefix
//   (scripts/store-faults.ts: a fraction F of requests fail every way, a new
//   seed per repeat).
// - scaling (stream-scale.ts): generated stores of 512^3, 1024^3, ... N^3
//   (default N = 1024; --size 2048, 4096), made once into .cache/bench-stream
//   (minutes for 2048^3, half an hour for 4096^3), within a 256 MB budget:
//   store bytes, GPU bytes after opening, the first surface after the
//   metadata, and three narrow isovalues refined as far as the budget goes.
// Median of the repeats after a discarded first.
import { existsSync, mkdirSync, readFileSync, writeFileSync } from 'node:fs';
import { createServer } from 'node:http';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { FaultInjector, faultPrefix } from '../scripts/store-faults.ts';
import { storesMiddleware } from '../scripts/vite-stores.ts';
import { describeAdapter } from '../src/gpu/device.ts';
import { requestNodeGpu } from '../src/gpu/node-gpu.ts';
import { Isosurface } from '../src/isosurface/isosurface.ts';
import { assembleLevelStream } from '../src/store/assemble.ts';
import { ChunkFetcher } from '../src/store/fetch/chunk-fetcher.ts';
import { chunksNeeded, neighbourhoodRanges } from '../src/store/plan.ts';
import { storeForLocation } from '../src/store/zarr/node-store.ts';
import { HttpStore } from '../src/store/zarr/http-store.ts';
import { openStore } from '../src/store/zarr/open-store.ts';
import { MeteredStore, SimulatedLinkStore } from '../src/store/zarr/stores.ts';
import { loadZfpStream } from '../src/zfp/gpu-stream.ts';
import { printTable, summarize, writeJson } from './lib/report.ts';
import { chunkedGpu, createChunkStream } from '../src/store/gpu-port.ts';
import { SCALE_HEADER, scaleRun, scaleStoreName, scaleTable } from './stream-scale.ts';
import { execFileSync } from 'node:child_process';
import { codecBench } from './stream-codec.ts';
import { type FlightRun, flightRun, medianRun, printFlight } from './stream-flight.ts';

const root = fileURLToPath(new URL('..', import.meta.url));
const args = process.argv.slice(2);
const opt = (name: string, def: string) => {
  const i = args.indexOf(`--${name}`);
  return i >= 0 ? args[i + 1] : def;
};
const size = Number(opt('size', '1024'));
const repeats = Number(opt('repeats', '3'));
const isoFraction = Number(opt('iso-fraction', '0.3'));
// the GPU memory of the whole stream, everything it holds: 256 MB
const budgetBytes = Number(opt('budget-mb', '256')) * 2 ** 20;
const only = opt('only', '');
const faultRate = Number(opt('faults', '0'));
const links = opt('links', 'localhost,link')
  .split(',')
  .map((l) => (l === 'link' ? '100 Mbit/s + 20 ms' : 'localhost'));
const jsonOut = opt('json', join(root, 'benchmarks/results/stream-swiftshader.json'));
const folder = join(root, '.cache/bench-stream');
mkdirSync(folder, { recursive: true });

function convert(input: string, name: string, extra: string[]): void {
  if (existsSync(join(folder, name, 'zarr.json'))) return;
  console.log(`converting ${input} -> ${name}`);
  execFileSync(
    process.execPath,
    [join(root, 'scripts/convert.mjs'), input, '--out', join(folder, name), '--quiet', '--chunk', '64', ...extra],
    { stdio: 'inherit' },
  );
}

async function serve(faults: FaultInjector) {
  const mw = storesMiddleware(folder, faults);
  const server = createServer((req, res) =>
    mw(req, res, () => {
      res.statusCode = 404;
      res.end();
    }),
  );
  await new Promise<void>((r) => server.listen(0, '127.0.0.1', () => r()));
  return { server, port: (server.address() as { port: number }).port };
}

/** --codec zstd,blosc,gzip: stores of lossless chunks against the zfp store (stream-codec.ts). */
async function codecMain(codecs: string[]) {
  const gpu = await requestNodeGpu({ label: 'bench.stream.codec' });
  const { server, port } = await serve(new FaultInjector());
  const codecSize = args.includes('--size') ? size : 256;
  const records = await codecBench(gpu, { root, folder, port, server, size: codecSize, repeats, codecs, links, budgetBytes });
  server.closeAllConnections();
  server.close();
  writeJson(opt('json', join(root, 'benchmarks/results/stream-codec-swiftshader.json')), {
    date: new Date().toISOString(),
    adapter: describeAdapter(gpu.adapter),
    size: codecSize,
    repeats,
    budgetBytes,
    records,
  });
  gpu.device.destroy();
}

async function main() {
  const gpu = await requestNodeGpu({ label: 'bench.stream' });
  convert(join(root, '../shared/data/volumes/bonsai_256x256x256_float32.rate4.zfp'), 'bonsai.zarr', ['--rate', '4']);
  const sizes: number[] = [];
  for (let n = 512; n <= size; n *= 2) sizes.push(n);
  if (only !== 'bonsai') for (const n of sizes) convert(`gen:${n}x${n}x${n}`, scaleStoreName(n), ['--rate', '1', '--shard', '8']);
  const faults = new FaultInjector();
  const { server, port } = await serve(faults);
  const rows: (string | number)[][] = [];
  const records: Record<string, unknown>[] = [];
  for (const name of ['bonsai.zarr'].filter((n) => !only || n.startsWith(only))) {
    // the chunk pool (ChunkedVolume): only the planned chunks, coarsest level first
    for (const link of links) {
      for (const rate of faultRate > 0 ? [0, faultRate] : [0]) {
        const first: number[] = [],
          full: number[] = [];
        let bytes = 0,
          storeBytes = 0,
          triangles = 0,
          iso = 0,
          planned = NaN,
          level0Chunks = 0,
          gpuBytes = 0,
          gpuPeak = 0,
          requests = 0,
          retries = 0;
        for (let r = 0; r < repeats; r++) {
          const url = `http://127.0.0.1:${port}/stores/${rate > 0 ? `${faultPrefix({ rate, seed: r + 1 })}/` : ''}${name}`;
          const inner = new HttpStore(url);
          const metered = new MeteredStore(
            link === 'localhost' ? inner : new SimulatedLinkStore(inner, { mbitPerSecond: 100, latencyMs: 20 }),
          );
          const t0 = performance.now();
          const store = await openStore(metered, url);
          const [lo, hi] = store.valueRange ?? [0, 1];
          iso = lo + isoFraction * (hi - lo);
          const fetcher = new ChunkFetcher(store);
          let chunks0 = 0;
          fetcher.onChunk((level, _c, _b, fromCache) => {
            if (level === 0 && !fromCache) chunks0++;
          });
          const port_ = chunkedGpu(gpu);
          const c = await createChunkStream(store, fetcher, port_, budgetBytes);
          let t1 = NaN;
          let stopped = '';
          c.onShown(() => {
            if (Number.isNaN(t1)) t1 = performance.now();
          });
          c.onProgress((p) => {
            if (p.phase === 'stopped') stopped = p.reason ?? '';
          });
          await c.setIsovalue(iso);
          const t2 = performance.now();
          if (c.shown?.level !== 0)
            throw new Error(`${name}: refinement stopped at level ${c.shown?.level}: ${stopped} (raise --budget-mb)`);
          triangles = c.shown.stats.triangles;
          first.push(t1 - t0);
          full.push(t2 - t0);
          bytes = metered.meter.bytes;
          requests = metered.meter.requests;
          retries = store.retries.retries;
          storeBytes = store.levels.reduce((a, l) => a + l.storedBytes, 0);
          level0Chunks = chunks0;
          gpuBytes = c.gpuBytes.total;
          gpuPeak = port_.meter.peak;
          const ranges = c.chunkRanges(0);
          planned = ranges ? chunksNeeded(neighbourhoodRanges(store.levels[0].layout.chunkGrid, ranges), iso).length : NaN;
          c.destroy();
        }
        const f = summarize(first),
          g = summarize(full);
        const faultText = rate > 0 ? `${(rate * 100).toFixed(0)}%` : '0';
        rows.push([
          name,
          link,
          faultText,
          f.median,
          g.median,
          bytes / storeBytes,
          `${level0Chunks} / ${planned}`,
          requests,
          retries,
          (gpuBytes / 2 ** 20).toFixed(1),
          (gpuPeak / 2 ** 20).toFixed(1),
          triangles,
        ]);
        console.log(
          `${name}, ${link}, faults ${faultText}: first surface ${f.median.toFixed(0)} ms, full resolution ${g.median.toFixed(0)} ms, fetched ${(bytes / storeBytes).toFixed(3)} of the store, level-0 chunks ${level0Chunks} / ${planned} planned, ${requests} requests, ${retries} retries, ${triangles} triangles`,
        );
        records.push({
          store: name,
          link,
          faultRate: rate,
          path: 'chunk pool',
          iso,
          firstSurfaceMs: f,
          fullSurfaceMs: g,
          bytesFetched: bytes,
          storeChunkBytes: storeBytes,
          level0ChunksFetched: level0Chunks,
          level0ChunksPlanned: planned,
          requests,
          retries,
          gpuBytes,
          gpuPeakBytes: gpuPeak,
          budgetBytes,
          triangles,
        });
      }
    }
    // in-core: level 0 as one stream, from disk
    // read from the folder, not 4096 requests at once through the little server
    const s = await openStore(storeForLocation(join(folder, name)), name);
    const lv = s.levels[0];
    const chunks: Uint8Array[] = [];
    for (let i = 0; i < lv.chunkCount; i++) chunks.push(await s.readChunk(0, i));
    const file = join(folder, `${name}.level0.zfp`);
    writeFileSync(
      file,
      assembleLevelStream(lv.layout, (c) => chunks[c]),
    );
    const [lo, hi] = s.valueRange ?? [0, 1];
    const times: number[] = [];
    for (let r = 0; r < repeats; r++) {
      const t0 = performance.now();
      const stream = loadZfpStream(gpu.device, new Uint8Array(readFileSync(file)), file);
      const surface = await Isosurface.create(gpu, stream, { memoryBudgetBytes: budgetBytes });
      await surface.compute(lo + isoFraction * (hi - lo));
      surface.destroy();
      stream.destroy();
      times.push(performance.now() - t0);
    }
    const t = summarize(times);
    rows.push([name, 'in-core (level 0 as one stream from disk)', '', NaN, t.median, NaN, '', NaN, NaN, '', '', NaN]);
    records.push({ store: name, link: 'in-core', fullSurfaceMs: t });
  }
  const scale = only === 'bonsai' ? [] : await scaleRun(gpu, folder, `http://127.0.0.1:${port}/stores`, sizes, links, repeats, budgetBytes);
  server.closeAllConnections();
  server.close();
  if (scale.length > 0)
    printTable(
      `bench:stream scaling, ${describeAdapter(gpu.adapter)}, median of ${repeats - 1} after a discarded first; the converter's gen: field, 64^3 chunks, rate 1, shards of 8^3; budget ${budgetBytes / 2 ** 20} MiB`,
      SCALE_HEADER,
      scaleTable(scale),
    );
  printTable(
    `bench:stream, ${describeAdapter(gpu.adapter)}, median of ${repeats - 1} after a discarded first; gen size ${size}^3; the store stream level by level (the page's and the CLI's path): the planned chunks into ChunkedVolume pools, coarsest level first; budget ${budgetBytes / 2 ** 20} MiB`,
    [
      'store',
      'link',
      'faults',
      'first surface ms',
      'full-res ms',
      'fetched / store',
      'L0 chunks fetched / planned',
      'requests',
      'retries',
      'GPU MiB',
      'peak MiB',
      'triangles',
    ],
    rows,
  );
  if (faultRate > 0) console.log(`faults injected: ${JSON.stringify(faults.injected)}, on ${JSON.stringify(faults.injectedOn)}`);
  writeJson(jsonOut, {
    date: new Date().toISOString(),
    adapter: describeAdapter(gpu.adapter),
    size,
    repeats,
    isoFraction,
    budgetBytes,
    faultRate,
    faultsInjected: faults.injected,
    records,
    scaling: scale,
  });
  gpu.device.destroy();
}
/** --flight: a scripted fly-through of a generated store refined by the view (stream-flight.ts). */
async function flightMain() {
  const gpu = await requestNodeGpu({ label: 'bench.stream.flight' });
  const n = args.includes('--size') ? size : 512;
  const name = scaleStoreName(n);
  convert(`gen:${n}x${n}x${n}`, name, ['--rate', '1', '--shard', '8']);
  const { server, port } = await serve(new FaultInjector());
  const iso = Number(opt('iso', '2.5'));
  const tolerance = Number(opt('tolerance', '1.5'));
  const flightRepeats = args.includes('--repeats') ? repeats : 2;
  const runs: FlightRun[] = [];
  for (const link of links) {
    const all: FlightRun[] = [];
    for (let r = 0; r <= flightRepeats; r++) {
      const run = await flightRun(gpu, `http://127.0.0.1:${port}/stores`, name, n, link, budgetBytes, iso, tolerance);
      if (r > 0) all.push(run); // the first is discarded (compilation, the server's disk cache)
    }
    const m = medianRun(all);
    printFlight(m);
    runs.push(m);
  }
  server.closeAllConnections();
  server.close();
  writeJson(opt('json', join(root, 'benchmarks/results/stream-flight-swiftshader.json')), {
    date: new Date().toISOString(),
    adapter: describeAdapter(gpu.adapter),
    size: n,
    iso,
    tolerancePx: tolerance,
    repeats: flightRepeats,
    budgetBytes,
    runs,
  });
  gpu.device.destroy();
}

const codecs = opt('codec', '');
if (codecs) await codecMain(codecs.split(','));
else if (args.includes('--flight')) await flightMain();
else await main();
