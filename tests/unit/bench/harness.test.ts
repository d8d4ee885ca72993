import { describe, expect, it } from 'vitest';
import { isovalueSequence } from '../../../src/bench/sequences.ts';
import { runBenchmark, type SurfaceEngine } from '../../../src/bench/harness.ts';

describe('benchmark sequences', () => {
  it('random is seeded, in range and float32', () => {
    const a = isovalueSequence('random', 100, [10, 20], 42);
    expect(a).toEqual(isovalueSequence('random', 100, [10, 20], 42));
    expect(a).not.toEqual(isovalueSequence('random', 100, [10, 20], 43));
    expect(a.every((v) => v >= 10 && v <= 20 && Math.fround(v) === v)).toBe(true);
  });
  it('sweeps cover the range in order', () => {
    const up = isovalueSequence('sweep-up', 5, [0, 1], 1);
    expect(up).toEqual([0, 0.25, 0.5, 0.75, 1]);
    expect(isovalueSequence('sweep-down', 5, [0, 1], 1)).toEqual([...up].reverse());
  });
  it('the harness resets per mode, discards the first record and summarizes the rest', async () => {
    const calls: string[] = [];
    const engine: SurfaceEngine = {
      resetCache: () => void calls.push('reset'),
      compute: async (iso) => {
        calls.push(`iso ${iso}`);
        return { activeBlocks: 10, newBlocks: iso < 0.5 ? 5 : 0, occupiedBlocks: 4, triangles: 100, gpuMs: iso * 10 };
      },
    };
    const r = await runBenchmark(engine, { modes: ['sweep-up', 'sweep-down'], count: 3, range: [0, 1], seed: 0 });
    expect(calls).toEqual(['reset', 'iso 0', 'iso 0.5', 'iso 1', 'reset', 'iso 1', 'iso 0.5', 'iso 0']);
    expect(r.records.filter((x) => x.discarded).length).toBe(2);
    const up = r.summaries[0];
    expect(up.count).toBe(2);
    expect(up.meanMs).toBeCloseTo(7.5);
    expect(up.meanHitRate).toBe(1);
    const down = r.summaries[1];
    expect(down.meanHitRate).toBeCloseTo(0.75); // iso 0.5 -> 1, iso 0 -> 0.5
  });
});
