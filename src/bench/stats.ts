// Median/mean of samples, optionally dropping the first (warm-up) run.
// Shared by the in-page harness, the CLI and the benchmarks/ scripts.
export interface Stats {
  samples: number[];
  median: number;
  mean: number;
  min: number;
  max: number;
}

export function summarize(all: number[], discardFirst = true): Stats {
  const samples = discardFirst && all.length > 1 ? all.slice(1) : all.slice();
  const sorted = [...samples].sort((a, b) => a - b);
  const mid = sorted.length >> 1;
  const median = sorted.length === 0 ? NaN : sorted.length % 2 ? sorted[mid] : (sorted[mid - 1] + sorted[mid]) / 2;
  const mean = samples.reduce((s, x) => s + x, 0) / Math.max(1, samples.length);
  return { samples, median, mean, min: sorted[0] ?? NaN, max: sorted[sorted.length - 1] ?? NaN };
}
