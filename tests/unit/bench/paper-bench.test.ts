// The pieces of `npm run bench:paper` that need no GPU: the paper's figures
// as quoted (every row verbatim in paper.tex), the data-driven isovalue range,
// --volume parsing, and the Markdown report of the committed full run
// (regenerated from its JSON: one table per paper table, the headline ratios).
import { existsSync, readFileSync } from 'node:fs';
import { join } from 'node:path';
import { describe, expect, test } from 'vitest';
import { checkAgainstPaper } from '../../../benchmarks/paper/paper-figures.ts';
import { writeReport } from '../../../benchmarks/paper/report.ts';
import type { PaperBenchResult } from '../../../benchmarks/paper/result.ts';
import { userVolume } from '../../../benchmarks/paper/volumes.ts';
import { interestingRange, meanAfterFirst } from '../../../src/examples/paper-bench/measure.ts';
import { ROOT } from '../mc/reference.ts';

describe('bench:paper', () => {
  test("every quoted figure of the paper appears verbatim in paper.tex", (ctx) => {
    const tex = join(ROOT, '..', 'shared', 'reference', 'paper.tex');
    if (!existsSync(tex)) return ctx.skip('paper.tex is not next to the repository');
    expect(checkAgainstPaper(tex)).toEqual([]);
  });

  test('the data-driven range: percentiles of the maxima of blocks with structure, not noise or background', () => {
    // A 16^3 volume: background 0 with noise below 1, a ramp from 10 to 100 along x in the middle.
    const dims: [number, number, number] = [16, 16, 16];
    const v = new Float32Array(16 ** 3);
    for (let z = 0; z < 16; z++)
      for (let y = 0; y < 16; y++)
        for (let x = 0; x < 16; x++) v[x + 16 * (y + 16 * z)] = (x * 7 + y * 3 + z) % 10 / 20 + (y >= 4 && y < 12 ? 10 + 6 * x : 0);
    const [lo, hi] = interestingRange(v, dims);
    expect(lo).toBeGreaterThan(10);
    expect(hi).toBeLessThanOrEqual(101);
    expect(hi).toBeGreaterThan(lo);
    // A constant volume has no range of interest beyond its value.
    expect(interestingRange(new Float32Array(64).fill(3), [4, 4, 4])).toEqual([3, 3]);
  });

  test('--volume FILE and FILE:lo,hi', () => {
    expect(userVolume('/d/a_8x8x8_uint8.raw')).toMatchObject({ path: '/d/a_8x8x8_uint8.raw', range: undefined, key: 'a-8x8x8-uint8-raw' });
    expect(userVolume('/d/b.zfp:-1.5,2e1')).toMatchObject({ path: '/d/b.zfp', range: [-1.5, 20], rangeSource: 'given with --volume' });
    expect(() => userVolume('/d/b.zfp:5,1')).toThrow(/lo < hi/);
  });

  test('the first sample is left out of the mean', () => {
    expect(meanAfterFirst([100, 1, 2, 3])).toBe(2);
    expect(meanAfterFirst([7])).toBe(7);
  });

  test('the committed full report is what its JSON gives', () => {
    const json = join(ROOT, 'benchmarks', 'results', '2026-11-21-swiftshader.json');
    const result = JSON.parse(readFileSync(json, 'utf8')) as PaperBenchResult;
    const md = writeReport(result);
    expect(md).toBe(readFileSync(json.replace(/\.json$/, '.md'), 'utf8'));
    for (const heading of ['## Headline ratios', '(paper §3.3.3, Fig. 6)', '(paper Table 2)', '(paper Table 3)', '(paper Table 5)']) expect(md).toContain(heading);
    expect(result.mode).toBe('full');
    expect(result.durations.totalSeconds).toBeLessThan(result.limits.seconds);
    expect(result.errors).toEqual([]);
    expect(result.volumes.map((v) => v.key)).toEqual(['fuel', 'hydrogen', 'bonsai']);
    // Every method computed the same surfaces.
    for (const n of result.naive) expect(n.trianglesMatchSerial).toBe(true);
    for (const b of result.block) expect(b.trianglesMatchSerial).toBe(true);
    for (const z of result.zfp) expect(z.bitIdentical).toBe(true);
  });
});
