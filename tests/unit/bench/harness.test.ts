import { describe, expect, it } from 'vitest';
import { isovalueSequence } from '../../../src/bench/sequences.ts';
import { recordsToCsv, runBenchmark, type SurfaceEngine } from '../../../src/bench/harness.ts';

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
  it('an engine that draws: a frame after each surface, frame and image (surface + frame) times, two more CSV columns', async () => {
    const calls: string[] = [];
    let frame = 0;
    const surface = (iso: number) => ({ activeBlocks: 10, newBlocks: 0, occupiedBlocks: 4, triangles: 100, gpuMs: iso * 10 });
    const engine: SurfaceEngine = {
      resetCache: () => void calls.push('reset'),
      compute: async (iso) => {
        calls.push(`iso ${iso}`);
        return surface(iso);
      },
      draw: async () => {
        calls.push('draw');
        return ++frame;
      },
    };
    const r = await runBenchmark(engine, { modes: ['sweep-up'], count: 4, range: [0, 1.5], seed: 0 });
    expect(calls).toEqual(['reset', 'iso 0', 'draw', 'iso 0.5', 'draw', 'iso 1', 'draw', 'iso 1.5', 'draw']);
    expect(r.records.map((x) => [x.frameMs, x.imageMs])).toEqual([
      [1, 1],
      [2, 7],
      [3, 13],
      [4, 19],
    ]);
    // the first left out, as for the surfaces
    expect(r.summaries[0]).toMatchObject({ meanFrameMs: 3, medianFrameMs: 3, meanImageMs: 13, medianImageMs: 13, meanMs: 10 });
    const csv = recordsToCsv(r.records).trim().split('\n');
    expect(csv[0]).toBe('mode,index,iso,gpuMs,wallMs,hitRate,activeBlocks,newBlocks,occupiedBlocks,triangles,discarded,frameMs,imageMs');
    expect(csv[2].endsWith(',false,2,7')).toBe(true);
    // an engine that does not draw: the records, summaries and CSV as before
    const plain = await runBenchmark(
      { resetCache: () => {}, compute: async (iso) => surface(iso) },
      { modes: ['sweep-up'], count: 2, range: [0, 1], seed: 0 },
    );
    expect(plain.records.every((x) => !('frameMs' in x) && !('imageMs' in x))).toBe(true);
    expect(plain.summaries[0].meanFrameMs).toBeUndefined();
    expect(recordsToCsv(plain.records).split('\n')[0]).toBe(
      'mode,index,iso,gpuMs,wallMs,hitRate,activeBlocks,newBlocks,occupiedBlocks,triangles,discarded',
    );
  });
});
