// bench:gpu --smoke (issue 39): the GPU benchmark built as the bundle a lent
// GPU machine runs (benchmarks/gpu/bundle.mjs: one file, Dawn outside) and
// run with Node on SwiftShader at tiny sizes, so neither the benchmark nor
// its bundling can rot between loans. Every figure must be present, finite
// and positive; every section must run; and each GPU result must equal its
// reference from outside: zfpy's decode (SHA-256 in shared/data/reference/
// mc.json), vtkMarchingCubes' triangle counts, CPU scans, compactions and a
// stable sort, the serial CPU marching cubes, and the memory budget.
import { spawnSync } from 'node:child_process';
import { mkdirSync, mkdtempSync, readdirSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, test } from 'vitest';
import type { GpuBenchRecord } from '../../../benchmarks/gpu/report.ts';
import { repoRoot, sharedData } from '../../helpers/python.ts';

const work = mkdtempSync(join(tmpdir(), 'bench-gpu-smoke-'));
// the bundle sits inside the checkout so that `webgpu` resolves from its node_modules, as on a device it resolves from .gpu-bundle's
const bundleDir = join(repoRoot, 'test-results', 'bench-gpu-smoke');
let record: GpuBenchRecord;
let output = '';

beforeAll(async () => {
  mkdirSync(bundleDir, { recursive: true });
  const { bundleBenchGpu } = await import('../../../benchmarks/gpu/bundle.mjs');
  await bundleBenchGpu(join(bundleDir, 'bench-gpu.mjs'));
  const out = join(work, 'out');
  const r = spawnSync(
    process.execPath,
    [
      join(bundleDir, 'bench-gpu.mjs'),
      '--smoke',
      '--out',
      out,
      '--work',
      join(work, 'work'),
      '--data',
      sharedData,
      '--python',
      join(repoRoot, '.venv-converter', 'bin', 'python'),
    ],
    { encoding: 'utf8', timeout: 240_000, env: { ...process.env, ZFPISO_ADAPTER: 'swiftshader' } },
  );
  output = `${r.stdout}\n${r.stderr}`;
  const json = readdirSync(out).find((f) => f.endsWith('-smoke.json'));
  if (!json) throw new Error(`bench:gpu --smoke wrote no record (exit ${r.status}):\n${output.slice(-4000)}`);
  record = JSON.parse(readFileSync(join(out, json), 'utf8')) as GpuBenchRecord;
}, 300_000);

afterAll(() => rmSync(work, { recursive: true, force: true }));

describe('bench:gpu --smoke (the bundled benchmark on SwiftShader)', () => {
  test('every section ran within the smoke allowance', () => {
    const gpuSections = record.sections.filter((s) => s.name !== 'page benchmark (Chromium)');
    expect(gpuSections.map((s) => s.name)).toEqual(['probe', 'zfp decode', 'primitives', 'surfaces', 'stream', 'lossless']);
    for (const s of gpuSections) expect(s.status, `${s.name}: ${s.reason ?? ''}\n${output.slice(-3000)}`).toBe('ran');
    // the page benchmark is reported, not silently dropped
    expect(record.sections.find((s) => s.name === 'page benchmark (Chromium)')?.reason).toBeTruthy();
    expect(record.wallSeconds).toBeLessThan(record.maxSeconds);
    expect(record.smoke).toBe(true);
    expect(record.gpu).toBe('swiftshader');
  });

  test('every figure is present, finite and positive, in every section', () => {
    for (const section of ['probe', 'zfp decode', 'primitives', 'surfaces', 'stream', 'lossless'])
      expect(record.figures.filter((f) => f.section === section).length, section).toBeGreaterThan(0);
    for (const f of record.figures) expect(Number.isFinite(f.value) && f.value > 0, `${f.section}: ${f.name} = ${f.value}`).toBe(true);
    // the primitives at each size and kernel family, the decodes of both volumes on both paths
    const prim = record.figures.filter((f) => f.section === 'primitives');
    for (const p of ['exclusive scan', 'stream compaction', 'radix sort-by-key'])
      for (const e of ['2^10', '2^12'])
        expect(
          prim.some((f) => f.name.startsWith(p) && f.name.includes(e)),
          `${p} ${e}`,
        ).toBe(true);
    const zfp = record.figures.filter((f) => f.section === 'zfp decode').map((f) => f.name);
    for (const what of ['whole volume hydrogen', 'sharded pool', 'whole volume gen_64'])
      for (const path of ['emulator path', 'gpu path'])
        expect(
          zfp.some((n) => n.includes(what) && n.includes(path)),
          `${what} ${path}`,
        ).toBe(true);
  });

  test('every GPU result equals its reference from outside', () => {
    const failed = record.checks.filter((c) => !c.ok);
    expect(failed, JSON.stringify(failed, null, 1)).toEqual([]);
    const names = record.checks.map((c) => c.name);
    const has = (part: string, n = 1) => expect(names.filter((c) => c.includes(part)).length, part).toBeGreaterThanOrEqual(n);
    has("the GPU decode equals zfpy's"); // SHA-256 from mc.json
    has('equal vtkMarchingCubes', 5); // fuel's five reference isovalues, block and naive MC
    has('equals the CPU reference', 12); // 3 primitives x 2 sizes x 2 kernel families
    has("the sharded pool's blocks equal the whole decode");
    has('naive MC equals the block pipeline', 2);
    has('the block pipeline equals the serial CPU MC');
    has('GPU peak within the budget', 3); // level by level, and two flight stops
    has('no uncaptured WebGPU error');
  });

  test('a record compares with itself figure by figure', () => {
    const r = spawnSync(
      process.execPath,
      [
        '--import',
        join(repoRoot, 'scripts/register-node-loaders.mjs'),
        join(repoRoot, 'benchmarks/gpu/run.ts'),
        '--compare',
        ...Array(2).fill(join(work, 'out', readdirSync(join(work, 'out')).find((f) => f.endsWith('.json'))!)),
      ],
      { encoding: 'utf8', timeout: 60_000 },
    );
    expect(r.status, r.stderr).toBe(0);
    const ratios = r.stdout.split('\n').filter((l) => /^(probe|zfp decode|primitives|surfaces|stream|lossless): /.test(l));
    expect(ratios.length).toBe(record.figures.length);
    for (const l of ratios) expect(l.trim().endsWith(' 1'), l).toBe(true);
  });
});
