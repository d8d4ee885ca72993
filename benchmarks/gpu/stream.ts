// bench:gpu's streamed surfaces: a generated N^3 store (the converter's gen:
// field, 64^3 chunks at rate 1 in shards, levels down to one chunk, made on
// the machine that runs the benchmark by the project's converter) served over
// HTTP on localhost, as bench:stream serves it:
// - the first streamed surface: the level stream's coarsest level after
//   the metadata, then as fine as the budget allows (the level-by-level
//   engine);
// - flight stops (the view's refinement, src/store/view/): the page's Fit and
//   the zoom into the corner of bench:stream --flight: time to the first
//   update and to the whole cut, chunks per level on screen, GPU peak against
//   the budget.
import { execFileSync } from 'node:child_process';
import { existsSync } from 'node:fs';
import { join } from 'node:path';
import { ChunkFetcher } from '../../src/store/fetch/chunk-fetcher.ts';
import { chunkedGpu, createChunkStream } from '../../src/store/gpu-port.ts';
import { openStore } from '../../src/store/zarr/open-store.ts';
import { flightRun } from '../stream-flight.ts';
import { linkStore } from '../stream-scale.ts';
import type { BenchRun } from './context.ts';
import { serveStores } from './serve.ts';

const SECTION = 'stream';
const ISO = 2.5;
const STOPS = ['fit', 'zoom 3 (corner)'];
const MiB = 2 ** 20;

/** The store, converted once into the work folder; seconds the converter took (0 when it was there). */
function makeStore(run: BenchRun, edge: number): { name: string; seconds: number } {
  const name = `gen${edge}-r1.zarr`;
  const out = join(run.paths.work, name);
  if (existsSync(join(out, 'zarr.json'))) return { name, seconds: 0 };
  const shard = Math.max(1, Math.min(8, edge / 64));
  const t0 = performance.now();
  console.log(`  converting gen:${edge}^3 (rate 1, 64^3 chunks, shards of ${shard}^3) with ${run.paths.python}...`);
  const converter = join(run.paths.root, 'converter');
  execFileSync(
    run.paths.python,
    ['-m', 'zfpzarr', `gen:${edge}x${edge}x${edge}`, '--out', out, '--rate', '1', '--chunk', '64', '--shard', String(shard), '--quiet'],
    {
      stdio: 'inherit',
      env: { ...process.env, PYTHONPATH: [converter, process.env.PYTHONPATH].filter(Boolean).join(':') },
      timeout: 300_000,
    },
  );
  if (!existsSync(join(out, 'zarr.json'))) throw new Error(`the converter wrote no store at ${out}`);
  return { name, seconds: (performance.now() - t0) / 1000 };
}

export async function streamSection(run: BenchRun): Promise<unknown> {
  const edge = run.plan.storeEdge;
  const budget = run.plan.storeBudgetBytes;
  const { name, seconds } = makeStore(run, edge);
  if (seconds > 0) console.log(`  converted in ${seconds.toFixed(1)} s`);
  const server = await serveStores(run.paths.work);
  const { base } = server;
  const rows: (string | number)[][] = [];
  try {
    // the first streamed surface (level by level), twice: the first run compiles the pipelines
    let first: Record<string, number> = {};
    for (let r = 0; r < 2; r++) {
      const url = `${base}/${name}`;
      const metered = linkStore(url, 'localhost');
      const t0 = performance.now();
      const store = await openStore(metered, url);
      const port = chunkedGpu(run.gpu);
      const c = await createChunkStream(store, new ChunkFetcher(store), port, budget);
      const t1 = performance.now();
      c.finest = c.coarsest;
      await c.setIsovalue(ISO);
      const t2 = performance.now();
      c.finest = 0;
      await c.setIsovalue(ISO);
      const t3 = performance.now();
      first = {
        openMs: t1 - t0,
        firstSurfaceMs: t2 - t1,
        coarsestLevel: c.coarsest,
        finestMs: t3 - t2,
        finestLevel: c.shown?.level ?? -1,
        triangles: c.shown?.stats.triangles ?? 0,
        bytesFetched: metered.meter.bytes,
        gpuPeakBytes: port.meter.peak,
      };
      c.destroy();
      store.close?.();
    }
    console.log(`  level by level: ${JSON.stringify(first)}`);
    run.figure(SECTION, `gen ${edge}^3: first streamed surface after the metadata (ms)`, first.firstSurfaceMs, 'ms');
    run.figure(SECTION, `gen ${edge}^3: to level ${first.finestLevel} (ms)`, first.finestMs, 'ms');
    run.check(
      SECTION,
      `gen ${edge}^3 level by level: GPU peak within the budget`,
      first.gpuPeakBytes <= budget,
      `${(first.gpuPeakBytes / MiB).toFixed(1)} of ${(budget / MiB).toFixed(0)} MiB`,
    );
    rows.push([
      'level by level',
      `coarsest (level ${first.coarsestLevel}) / level ${first.finestLevel}`,
      first.firstSurfaceMs,
      first.finestMs,
      (first.bytesFetched / MiB).toFixed(1),
      (first.gpuPeakBytes / MiB).toFixed(1),
      '',
      first.triangles,
    ]);
    // flight stops (the first flight compiles; the second is measured)
    let flight = await flightRun(run.gpu, base, name, edge, 'localhost', budget, ISO, undefined, STOPS);
    flight = await flightRun(run.gpu, base, name, edge, 'localhost', budget, ISO, undefined, STOPS);
    for (const s of flight.stops) {
      if (Number.isNaN(s.firstUpdateMs) && s.bytesFetched === 0) {
        // no step shown, nothing fetched: the stop's cut was on screen already (a small store), no time to report
        run.notes.push(`stream: the flight stop "${s.name}" kept the cut already on screen (nothing to fetch or compute)`);
      } else {
        run.figure(SECTION, `gen ${edge}^3 flight stop ${s.name}: first update (ms)`, s.firstUpdateMs, 'ms');
        run.figure(SECTION, `gen ${edge}^3 flight stop ${s.name}: whole cut (ms)`, s.fullViewMs, 'ms');
      }
      run.check(
        SECTION,
        `gen ${edge}^3 flight stop ${s.name}: GPU peak within the budget`,
        s.gpuPeakBytes <= budget,
        `${(s.gpuPeakBytes / MiB).toFixed(1)} of ${(budget / MiB).toFixed(0)} MiB`,
      );
      rows.push([
        `flight: ${s.name}`,
        s.chunksPerLevel.join('/'),
        s.firstUpdateMs,
        s.fullViewMs,
        (s.bytesFetched / MiB).toFixed(1),
        (s.gpuPeakBytes / MiB).toFixed(1),
        s.longestTaskMs,
        '',
      ]);
    }
    run.table({
      title: `streamed gen ${edge}^3 store (localhost, budget ${(budget / MiB).toFixed(0)} MiB, iso ${ISO}; second run of each)`,
      header: ['what', 'levels / chunks per level', 'first ms', 'whole ms', 'fetched MiB', 'GPU peak MiB', 'longest task ms', 'triangles'],
      rows,
    });
    return { store: name, convertSeconds: seconds, budgetBytes: budget, iso: ISO, levelByLevel: first, flight };
  } finally {
    server.close();
  }
}
