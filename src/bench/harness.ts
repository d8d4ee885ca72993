// The isosurface benchmark harness, shared by the page and `cli bench`: runs
// each mode's sequence on a fresh cache, records every isovalue, discards the
// first (pipeline warm-up) from the summaries. An engine that can draw
// (`SurfaceEngine.draw`) also has one image drawn after each surface: the
// records then hold the frame's GPU time and the time per image (surface +
// frame), the summaries their mean and median, the CSV two more columns.
import { summarize } from './stats.ts';
import { isovalueSequence, type BenchMode } from './sequences.ts';
import { hitRate } from '../isosurface/types.ts';

/** What one surface computation reports (from the GPU statistics). */
export interface SurfaceStats {
  activeBlocks: number;
  newBlocks: number;
  occupiedBlocks: number;
  triangles: number;
  /** GPU time of the whole computation in ms (timestamps or queue wall time). */
  gpuMs: number;
}

/** What the harness drives: the Isosurface of the loaded volume. */
export interface SurfaceEngine {
  /** Empties the block cache so every mode starts cold. */
  resetCache(): Promise<void> | void;
  /** Computes the surface at `iso` and resolves with its statistics. */
  compute(iso: number): Promise<SurfaceStats>;
  /**
   * Draws one image of the surface computed last (after compute resolved)
   * and resolves with that frame's GPU time in ms (timestamps around its
   * render pass where the device has them, else the queue's wall time from
   * submit to done). Without it the harness times surfaces only.
   */
  draw?(): Promise<number>;
}

export interface BenchRecord extends SurfaceStats {
  mode: BenchMode;
  index: number;
  iso: number;
  /** 1 - new/active (1 when no block is active). */
  hitRate: number;
  /** Wall time from request to statistics, ms. */
  wallMs: number;
  /** The first record of each mode is excluded from the summary. */
  discarded: boolean;
  /** An engine that draws: the GPU ms of the image drawn after this surface. */
  frameMs?: number;
  /** An engine that draws: the time per image, surface + frame (gpuMs + frameMs). */
  imageMs?: number;
}

export interface BenchSummary {
  mode: BenchMode;
  count: number;
  meanMs: number;
  medianMs: number;
  meanWallMs: number;
  meanHitRate: number;
  meanActiveBlocks: number;
  meanNewBlocks: number;
  meanOccupiedBlocks: number;
  meanTriangles: number;
  /** An engine that draws: mean and median of frameMs and of imageMs (surface + frame). */
  meanFrameMs?: number;
  medianFrameMs?: number;
  meanImageMs?: number;
  medianImageMs?: number;
}

export interface BenchOptions {
  modes: BenchMode[];
  count: number;
  range: [number, number];
  seed: number;
  onProgress?: (done: number, total: number, last: BenchRecord) => void;
  /** Checked between surfaces; return true to stop early. */
  cancelled?: () => boolean;
}

export interface BenchResult {
  options: { modes: BenchMode[]; count: number; range: [number, number]; seed: number };
  records: BenchRecord[];
  summaries: BenchSummary[];
}

export function summarizeMode(mode: BenchMode, records: BenchRecord[]): BenchSummary {
  const kept = records.filter((r) => r.mode === mode && !r.discarded);
  const mean = (f: (r: BenchRecord) => number) => kept.reduce((s, r) => s + f(r), 0) / Math.max(1, kept.length);
  const gpu = summarize(
    kept.map((r) => r.gpuMs),
    false,
  );
  const drawn = kept.length > 0 && kept.every((r) => r.frameMs !== undefined);
  const frame = drawn
    ? summarize(
        kept.map((r) => r.frameMs ?? 0),
        false,
      )
    : undefined;
  const image = drawn
    ? summarize(
        kept.map((r) => r.imageMs ?? 0),
        false,
      )
    : undefined;
  return {
    mode,
    count: kept.length,
    meanMs: gpu.mean,
    medianMs: gpu.median,
    meanWallMs: mean((r) => r.wallMs),
    meanHitRate: mean((r) => r.hitRate),
    meanActiveBlocks: mean((r) => r.activeBlocks),
    meanNewBlocks: mean((r) => r.newBlocks),
    meanOccupiedBlocks: mean((r) => r.occupiedBlocks),
    meanTriangles: mean((r) => r.triangles),
    ...(frame && image
      ? { meanFrameMs: frame.mean, medianFrameMs: frame.median, meanImageMs: image.mean, medianImageMs: image.median }
      : {}),
  };
}

export async function runBenchmark(engine: SurfaceEngine, options: BenchOptions): Promise<BenchResult> {
  const records: BenchRecord[] = [];
  const total = options.modes.length * options.count;
  for (const mode of options.modes) {
    await engine.resetCache();
    const isovalues = isovalueSequence(mode, options.count, options.range, options.seed);
    for (let index = 0; index < isovalues.length; index++) {
      if (options.cancelled?.()) break;
      const iso = isovalues[index];
      const start = performance.now();
      const stats = await engine.compute(iso);
      const wallMs = performance.now() - start;
      // one image of that surface, after it (the surface's wall time leaves the frame out)
      const frameMs = engine.draw ? await engine.draw() : undefined;
      const record: BenchRecord = {
        mode,
        index,
        iso,
        ...stats,
        hitRate: hitRate(stats.activeBlocks, stats.newBlocks),
        wallMs,
        discarded: index === 0,
        ...(frameMs === undefined ? {} : { frameMs, imageMs: stats.gpuMs + frameMs }),
      };
      records.push(record);
      options.onProgress?.(records.length, total, record);
    }
  }
  const { onProgress: _p, cancelled: _c, ...plain } = options;
  return { options: plain, records, summaries: options.modes.map((m) => summarizeMode(m, records)) };
}

const CSV_COLUMNS: (keyof BenchRecord)[] = [
  'mode',
  'index',
  'iso',
  'gpuMs',
  'wallMs',
  'hitRate',
  'activeBlocks',
  'newBlocks',
  'occupiedBlocks',
  'triangles',
  'discarded',
];

/** Records that carry frame times (an engine that draws) get frameMs and imageMs after the other columns. */
export function recordsToCsv(records: BenchRecord[]): string {
  const drawn = records.length > 0 && records.every((r) => r.frameMs !== undefined);
  const columns: (keyof BenchRecord)[] = drawn ? [...CSV_COLUMNS, 'frameMs', 'imageMs'] : CSV_COLUMNS;
  const lines = [columns.join(',')];
  for (const r of records) lines.push(columns.map((c) => String(r[c])).join(','));
  return lines.join('\n') + '\n';
}
