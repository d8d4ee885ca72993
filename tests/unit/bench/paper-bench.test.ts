// The pieces of `npm run bench:paper` that need no GPU: the paper's figures
// as quoted (every row verbatim in paper.tex), the data-driven isovalue range,
// --volume parsing, and the committed full run (every figure its report
// claims recomputed from the raw samples of its JSON).
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
  test('every quoted figure of the paper appears verbatim in paper.tex', (ctx) => {
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
        for (let x = 0; x < 16; x++) v[x + 16 * (y + 16 * z)] = ((x * 7 + y * 3 + z) % 10) / 20 + (y >= 4 && y < 12 ? 10 + 6 * x : 0);
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

  // The committed full run: every figure its report claims is recomputed here
  // from the raw samples the JSON keeps (per-isovalue times and triangle
  // counts), with this test's own arithmetic, and every cross-method claim
  // (same triangles as the serial MC) is checked sample by sample.
  test('the committed full run: headline ratios, means and "same triangles" recomputed from its raw samples', () => {
    const json = join(ROOT, 'benchmarks', 'results', '2026-11-21-swiftshader.json');
    const r = JSON.parse(readFileSync(json, 'utf8')) as PaperBenchResult;
    const avg = (xs: number[]) => xs.reduce((a, b) => a + b, 0) / xs.length;
    const afterFirst = (xs: number[]) => avg(xs.slice(1));
    const close = (got: number | undefined, want: number, what: string) => expect(got, what).toBeCloseTo(want, 9);
    expect(r.volumes.map((v) => v.key)).toEqual(['fuel', 'hydrogen', 'bonsai']);
    expect(r.errors).toEqual([]);

    // Serial MC: per-volume means of the samples after the first; the headline is the mean of the per-volume ratios.
    for (const s of r.serial) {
      close(s.means.native, afterFirst(s.native!.ms), `${s.volume} native mean`);
      close(s.means.wasmNode, afterFirst(s.wasmNode.ms), `${s.volume} wasm mean`);
      close(s.means.jsNode, afterFirst(s.jsNode.ms), `${s.volume} js mean`);
      // Every method found the same triangles at every isovalue.
      expect(s.wasmNode.triangles, s.volume).toEqual(s.native!.triangles);
      expect(s.jsNode.triangles, s.volume).toEqual(s.native!.triangles);
      if (s.wasmChromium) expect(s.wasmChromium.triangles).toEqual(s.native!.triangles);
    }
    const ratioOf = (num: (s: (typeof r.serial)[number]) => number[], den: (s: (typeof r.serial)[number]) => number[]) =>
      avg(r.serial.map((s) => afterFirst(num(s)) / afterFirst(den(s))));
    close(
      r.headline.serial.wasmNodeVsNative,
      ratioOf(
        (s) => s.wasmNode.ms,
        (s) => s.native!.ms,
      ),
      'wasm / native',
    );
    close(
      r.headline.serial.jsNodeVsNative,
      ratioOf(
        (s) => s.jsNode.ms,
        (s) => s.native!.ms,
      ),
      'js / native',
    );
    close(
      r.headline.serial.jsNodeVsWasmNode,
      ratioOf(
        (s) => s.jsNode.ms,
        (s) => s.wasmNode.ms,
      ),
      'js / wasm',
    );
    close(
      r.headline.serial.wasmChromiumVsNative,
      ratioOf(
        (s) => s.wasmChromium!.ms,
        (s) => s.native!.ms,
      ),
      'wasm chromium / native',
    );

    // Naive GPU MC: its triangles are the serial MC's at the same isovalues.
    for (const n of r.naive) {
      const s = r.serial.find((x) => x.volume === n.volume)!;
      expect(n.isovalues).toEqual(s.isovalues.slice(0, n.isovalues.length));
      const k = n.triangles.length;
      expect(n.triangles, n.volume).toEqual(s.native!.triangles.slice(0, k));
      expect(n.trianglesMatchSerial).toBe(true);
    }
    // Block-compressed: every random-mode surface has the serial MC's triangles; naive / block over the same surfaces.
    for (const b of r.block) {
      const s = r.serial.find((x) => x.volume === b.volume)!;
      const random = b.records.filter((x) => x.mode === 'random');
      expect(random.length).toBeGreaterThan(1);
      for (const x of random)
        if (x.index < s.native!.triangles.length) expect(x.triangles, `${b.volume} #${x.index}`).toBe(s.native!.triangles[x.index]);
      const n = r.naive.find((x) => x.volume === b.volume)!;
      const same = random.filter((x) => !x.discarded && x.index < n.ms.length);
      const h = r.headline.naiveVsBlock.find((x) => x.volume === b.volume)!;
      expect(h.surfaces).toBe(same.length);
      close(h.blockMs, avg(same.map((x) => x.gpuMs)), `${b.volume} block ms`);
      close(h.naiveMs, avg(n.ms.slice(1, 1 + same.length)), `${b.volume} naive ms`);
      close(h.ratio, h.naiveMs / h.blockMs, `${b.volume} naive / block`);
      for (const m of b.summaries) {
        const kept = b.records.filter((x) => x.mode === m.mode && !x.discarded);
        expect(m.count).toBe(kept.length);
        close(m.meanMs, avg(kept.map((x) => x.gpuMs)), `${b.volume} ${m.mode} mean ms`);
        close(m.meanTriangles, avg(kept.map((x) => x.triangles)), `${b.volume} ${m.mode} triangles`);
        close(m.meanHitRate, avg(kept.map((x) => x.hitRate)), `${b.volume} ${m.mode} hit rate`);
      }
    }
    // zfp: MB/s from the decoded float bytes and the mean time after the first; the headline averages the ratios over volumes.
    const mbps = (bytes: number, ms: number[]) => bytes / 1e6 / (afterFirst(ms) / 1000);
    for (const z of r.zfp) {
      close(z.mbps.webgpu, mbps(z.floatBytes, z.webgpuMs), `${z.volume} rate ${z.rate} webgpu MB/s`);
      close(z.mbps.zfpySerial, mbps(z.floatBytes, z.zfpyMs), `${z.volume} rate ${z.rate} zfpy MB/s`);
      close(z.mbps.wasmNode, mbps(z.floatBytes, z.wasmNodeMs), `${z.volume} rate ${z.rate} wasm MB/s`);
    }
    for (const h of r.headline.zfp) {
      const zs = r.zfp.filter((z) => z.rate === h.rate);
      close(
        h.webgpuVsSerial,
        avg(zs.map((z) => mbps(z.floatBytes, z.webgpuMs) / mbps(z.floatBytes, z.zfpyMs))),
        `rate ${h.rate} webgpu / serial`,
      );
      close(
        h.wasmNodeVsSerial,
        avg(zs.map((z) => mbps(z.floatBytes, z.wasmNodeMs) / mbps(z.floatBytes, z.zfpyMs))),
        `rate ${h.rate} wasm / serial`,
      );
    }
    // The report shows these numbers (its tables are written from the same JSON).
    const md = writeReport(r);
    for (const h of r.headline.naiveVsBlock) expect(md).toContain(`= ${h.ratio >= 10 ? h.ratio.toFixed(0) : h.ratio.toFixed(2)}×`);
  });
});
