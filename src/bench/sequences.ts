// Isovalue sequences of the paper's benchmark (section 4.6): 100 random
// isovalues, a sweep up and a sweep down over a range of interest. Seeded,
// so the page and the CLI compute exactly the same surfaces.
import { mulberry32 } from '../util/random.ts';

export type BenchMode = 'random' | 'sweep-up' | 'sweep-down';
export const BENCH_MODES: readonly BenchMode[] = ['random', 'sweep-up', 'sweep-down'];

export function isBenchMode(s: string): s is BenchMode {
  return (BENCH_MODES as readonly string[]).includes(s);
}

/** Isovalues are float32, as the GPU compares them. */
export function isovalueSequence(mode: BenchMode, count: number, range: [number, number], seed: number): number[] {
  const [lo, hi] = range;
  const out: number[] = [];
  if (mode === 'random') {
    const random = mulberry32(seed);
    for (let i = 0; i < count; i++) out.push(Math.fround(lo + (hi - lo) * random()));
  } else {
    for (let i = 0; i < count; i++) {
      const t = count === 1 ? 0 : i / (count - 1);
      out.push(Math.fround(mode === 'sweep-up' ? lo + (hi - lo) * t : hi - (hi - lo) * t));
    }
  }
  return out;
}
