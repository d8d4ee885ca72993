// Block-compressed isosurfaces (the paper's Table 5): the shared harness
// (src/bench/harness.ts, the same as `cli bench` and the page's Benchmark
// button) on the Isosurface pipeline: random, sweep up and sweep down, each
// from a cold cache, seeded, first surface of each mode discarded.
import { runBenchmark, type BenchRecord, type BenchSummary, type SurfaceEngine } from '../../src/bench/harness.ts';
import type { BenchMode } from '../../src/bench/sequences.ts';
import type { GpuContext } from '../../src/gpu/device.ts';
import { Isosurface } from '../../src/isosurface/isosurface.ts';
import type { IsosurfaceStats } from '../../src/isosurface/types.ts';
import type { PreparedVolume } from './volumes.ts';

export interface BlockResult {
  volume: string;
  count: number;
  seed: number;
  range: [number, number];
  summaries: BenchSummary[];
  /** Per record: mode, index, iso, gpuMs, wallMs, hitRate, blocks, triangles. */
  records: Omit<BenchRecord, never>[];
  /** Mean ms per stage per mode (kept surfaces). */
  stages: Record<string, Record<string, number>>;
  blockCount: number;
  memory: { fixedBytes?: number; cacheBytesMax: number; vertexBytesMax: number };
}

export async function runBlock(
  gpu: GpuContext,
  v: PreparedVolume,
  modes: BenchMode[],
  count: number,
  seed: number,
  opts: {
    capSecondsPerMode?: number;
    onProgress?: (mode: BenchMode, done: number, total: number) => void;
    /**
     * Called after each surface of the random mode with its isovalue and index,
     * to measure another method on the same isovalue right then (the naive MC):
     * both then see the same machine load. Returns the ms it took, which is
     * taken out of that record's wall time and of the mode's time cap.
     */
    pairRandom?: (iso: number, index: number) => Promise<number | undefined>;
  } = {},
): Promise<BlockResult> {
  const iso = await Isosurface.create(gpu, v.stream);
  try {
    // One harness run per mode (each from a cold cache, as the harness does), so a time cap ends one mode early, not the others.
    const result = { records: [] as BenchRecord[], summaries: [] as BenchSummary[] };
    for (const mode of modes) {
      const start = performance.now();
      const cap = (opts.capSecondsPerMode ?? Infinity) * 1000;
      let pairedMs = 0;
      const spent: number[] = [];
      let index = 0;
      const engine: SurfaceEngine = {
        resetCache: () => iso.resetCache(),
        compute: async (x) => {
          const stats = await iso.compute(x);
          const extra = mode === 'random' && opts.pairRandom ? ((await opts.pairRandom(x, index)) ?? 0) : 0;
          spent.push(extra);
          pairedMs += extra;
          index++;
          return stats;
        },
      };
      const one = await runBenchmark(engine, {
        modes: [mode],
        count,
        range: v.range,
        seed,
        onProgress: (d, t) => opts.onProgress?.(mode, d, t),
        cancelled: () => performance.now() - start - pairedMs > cap,
      });
      one.records.forEach((r, i) => (r.wallMs -= spent[i] ?? 0));
      result.records.push(...one.records);
      result.summaries.push(
        ...one.summaries.map((sum) => ({
          ...sum,
          meanWallMs: sum.meanWallMs - spent.slice(1).reduce((a, b) => a + b, 0) / Math.max(1, spent.length - 1),
        })),
      );
    }
    const stages: Record<string, Record<string, number>> = {};
    let cacheBytesMax = 0;
    let vertexBytesMax = 0;
    let fixedBytes: number | undefined;
    for (const mode of modes) {
      const kept = result.records.filter((r) => r.mode === mode && !r.discarded) as unknown as (BenchRecord & IsosurfaceStats)[];
      const acc: Record<string, number> = {};
      for (const r of kept) for (const s of r.stages ?? []) acc[s.label] = (acc[s.label] ?? 0) + s.ms / Math.max(1, kept.length);
      stages[mode] = acc;
    }
    const records = result.records.map((r) => {
      const s = r as unknown as BenchRecord & IsosurfaceStats;
      cacheBytesMax = Math.max(cacheBytesMax, s.cacheBytes ?? 0);
      vertexBytesMax = Math.max(vertexBytesMax, s.vertexBytes ?? 0);
      fixedBytes ??= s.fixedBytes;
      return {
        mode: r.mode,
        index: r.index,
        iso: r.iso,
        gpuMs: r.gpuMs,
        wallMs: r.wallMs,
        hitRate: r.hitRate,
        activeBlocks: r.activeBlocks,
        newBlocks: r.newBlocks,
        occupiedBlocks: r.occupiedBlocks,
        triangles: r.triangles,
        discarded: r.discarded,
      };
    });
    return {
      volume: v.key,
      count,
      seed,
      range: v.range,
      summaries: result.summaries,
      records,
      stages,
      blockCount: iso.info.blockCount,
      memory: { fixedBytes, cacheBytesMax, vertexBytesMax },
    };
  } finally {
    iso.destroy();
  }
}
