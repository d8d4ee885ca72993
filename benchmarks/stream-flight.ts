// `npm run bench:stream -- --flight [--size N] [--repeats R] [--budget-mb M] [--links localhost,link] [--tolerance PX]`:
// a scripted fly-through of a generated N^3 store (default 512; the issue's
// 2048 with --size 2048, converted once into .cache/bench-stream, minutes)
// refined by the view (src/store/view/, the page's and the CLI's path): the
// page's Fit of the whole volume, three zoom steps into the +x +y +z corner,
// two orbit steps around it, and back out to Fit, each on a 1280x800 canvas
// at the default tolerance. Per camera stop: time from the stop to the
// view's whole cut on screen and to its first update, bytes fetched (against
// level 0's size), GPU bytes held and their peak (against the budget), the
// cut's chunks per level; and, while it streams, the gaps of a 4 ms timer on
// the event loop (what a page's frames would wait for: median, p95 and the
// longest task). Served over HTTP on localhost and through the simulated
// 100 Mbit/s link. Median of the repeats after a discarded first.
import { quat } from 'gl-matrix';
import type { GpuContext } from '../src/gpu/device.ts';
import type { Isosurface } from '../src/isosurface/isosurface.ts';
import type { IsosurfaceStats } from '../src/isosurface/types.ts';
import { ChunkFetcher } from '../src/store/fetch/chunk-fetcher.ts';
import { chunkedGpu } from '../src/store/gpu-port.ts';
import { cameraForBox, cameraFromView, fitBox0, sceneRadiusOf, type ViewCameraState } from '../src/store/view/camera.ts';
import { DEFAULT_VIEWPORT } from '../src/store/view/view-request.ts';
import { DEFAULT_TOLERANCE_PX, StoreStream } from '../src/store/stream/store-stream.ts';
import { openStore } from '../src/store/zarr/open-store.ts';
import type { ChunkedVolume } from '../src/zfp/chunked-volume.ts';
import { printTable, summarize } from './lib/report.ts';
import { linkStore } from './stream-scale.ts';

const MiB = 2 ** 20;

export interface FlightStop {
  name: string;
  /** From the camera stop to the first step shown, and to the view's whole cut. */
  firstUpdateMs: number;
  fullViewMs: number;
  bytesFetched: number;
  gpuBytes: number;
  gpuPeakBytes: number;
  chunksPerLevel: number[];
  limitedByBudget: boolean;
  /** Event-loop gaps of a 4 ms timer while this stop streamed (ms). */
  gapMedianMs: number;
  gapP95Ms: number;
  longestTaskMs: number;
  stopped: string | null;
}

export interface FlightRun {
  size: number;
  link: string;
  level0Bytes: number;
  budgetBytes: number;
  stops: FlightStop[];
}

/** The flight's cameras: page states over a volume of `size`^3 voxels of size 1. */
export function flightCameras(size: number): { name: string; state: ViewCameraState }[] {
  const dims: [number, number, number] = [size, size, size];
  const fit = cameraForBox(fitBox0({ dims }, 0), [1, 1, 1], DEFAULT_VIEWPORT).state;
  const corner = (size - 1) * 0.85;
  const toward = (t: number, distance: number): ViewCameraState => ({
    rotation: [...fit.rotation],
    target: fit.target.map((c) => c + (corner - c) * t) as [number, number, number],
    distance: fit.distance * distance,
  });
  const orbit = (base: ViewCameraState, degrees: number): ViewCameraState => {
    const q = quat.fromValues(...base.rotation);
    const turn = quat.setAxisAngle(quat.create(), [0, 1, 0], (degrees * Math.PI) / 180);
    const r = quat.multiply(quat.create(), q, turn);
    return { ...base, rotation: [r[0], r[1], r[2], r[3]] };
  };
  const close = toward(1, 0.12);
  return [
    { name: 'fit', state: fit },
    { name: 'zoom 1', state: toward(0.4, 0.5) },
    { name: 'zoom 2', state: toward(0.75, 0.25) },
    { name: 'zoom 3 (corner)', state: close },
    { name: 'orbit 20°', state: orbit(close, 20) },
    { name: 'orbit 40°', state: orbit(close, 40) },
    { name: 'zoom out (fit)', state: fit },
  ];
}

function percentile(sorted: number[], p: number): number {
  if (sorted.length === 0) return 0;
  return sorted[Math.min(sorted.length - 1, Math.floor(p * sorted.length))];
}

export async function flightRun(
  gpu: GpuContext,
  baseUrl: string,
  name: string,
  size: number,
  link: string,
  budgetBytes: number,
  iso: number,
  tolerancePx = DEFAULT_TOLERANCE_PX,
  /** Only these stops (by name), in the flight's order; all when absent. */
  onlyStops?: readonly string[],
): Promise<FlightRun> {
  const url = `${baseUrl}/${name}`;
  const metered = linkStore(url, link);
  const store = await openStore(metered, url);
  const fetcher = new ChunkFetcher(store);
  const port = chunkedGpu(gpu);
  const stream = await StoreStream.byView<ChunkedVolume, IsosurfaceStats, Isosurface>(store, fetcher, port, budgetBytes);
  let stopped: string | null = null;
  stream.onProgress((p) => {
    if (p.phase === 'stopped') stopped = p.reason ?? 'stopped';
  });
  const sceneRadius = sceneRadiusOf(fitBox0(store.levels[0].layout, 0), store.voxelSize);
  const stops: FlightStop[] = [];
  let first = true;
  for (const cam of flightCameras(size).filter((c) => !onlyStops || onlyStops.includes(c.name))) {
    stopped = null;
    const spec = { camera: cameraFromView(cam.state, DEFAULT_VIEWPORT, sceneRadius), tolerancePx };
    const bytes0 = metered.meter.bytes;
    port.meter.peak = port.meter.bytes;
    const gaps: number[] = [];
    let last = performance.now();
    const ticker = setInterval(() => {
      const now = performance.now();
      gaps.push(now - last);
      last = now;
    }, 4);
    const t0 = performance.now();
    let firstUpdate = Number.NaN;
    const off = stream.onShown(() => {
      if (Number.isNaN(firstUpdate)) firstUpdate = performance.now() - t0;
    });
    await stream.setView(spec);
    if (first) {
      await stream.setIsovalue(iso);
      first = false;
    }
    const fullViewMs = performance.now() - t0;
    clearInterval(ticker);
    off();
    const shown = stream.shown;
    gaps.sort((a, b) => a - b);
    stops.push({
      name: cam.name,
      firstUpdateMs: Math.round(firstUpdate),
      fullViewMs: Math.round(fullViewMs),
      bytesFetched: metered.meter.bytes - bytes0,
      gpuBytes: port.meter.bytes,
      gpuPeakBytes: port.meter.peak,
      chunksPerLevel: store.levels.map((_, L) => shown?.levels.find((l) => l.level === L)?.drawn.length ?? 0),
      limitedByBudget: shown?.cut?.limitedByBudget ?? false,
      gapMedianMs: Number(percentile(gaps, 0.5).toFixed(1)),
      gapP95Ms: Number(percentile(gaps, 0.95).toFixed(1)),
      longestTaskMs: Number((gaps.at(-1) ?? 0).toFixed(1)),
      stopped,
    });
  }
  stream.destroy();
  store.close?.();
  const L0 = store.levels[0];
  return { size, link, level0Bytes: L0.storedBytes, budgetBytes, stops };
}

/** Median per stop over the runs (each figure on its own). */
export function medianRun(runs: FlightRun[]): FlightRun {
  const med = (xs: number[]) => summarize(xs, false).median;
  const base = runs[0];
  return {
    ...base,
    stops: base.stops.map((stop, i) => {
      const all = runs.map((r) => r.stops[i]);
      return {
        ...stop,
        firstUpdateMs: med(all.map((s) => s.firstUpdateMs)),
        fullViewMs: med(all.map((s) => s.fullViewMs)),
        bytesFetched: med(all.map((s) => s.bytesFetched)),
        gpuPeakBytes: med(all.map((s) => s.gpuPeakBytes)),
        gapMedianMs: med(all.map((s) => s.gapMedianMs)),
        gapP95Ms: med(all.map((s) => s.gapP95Ms)),
        longestTaskMs: med(all.map((s) => s.longestTaskMs)),
      };
    }),
  };
}

export function printFlight(run: FlightRun): void {
  printTable(
    `fly-through of gen ${run.size}^3 (${run.link}); level 0 is ${(run.level0Bytes / MiB).toFixed(1)} MiB, budget ${(run.budgetBytes / MiB).toFixed(0)} MiB`,
    [
      'stop',
      'first update ms',
      'full view ms',
      'fetched MiB',
      'GPU MiB',
      'GPU peak MiB',
      'chunks per level',
      'budget binds',
      'gap median ms',
      'gap p95 ms',
      'longest task ms',
    ],
    run.stops.map((s) => [
      s.name,
      s.firstUpdateMs,
      s.fullViewMs,
      (s.bytesFetched / MiB).toFixed(2),
      (s.gpuBytes / MiB).toFixed(1),
      (s.gpuPeakBytes / MiB).toFixed(1),
      s.chunksPerLevel.join('/'),
      s.limitedByBudget ? 'yes' : 'no',
      s.gapMedianMs,
      s.gapP95Ms,
      s.longestTaskMs,
    ]),
  );
}
