// `npm run bench:gpu`: the product measured on the GPU at hand, in one command
// that runs within a time allowance (8 minutes by default): a probe of the
// adapter, zfp decode, the GPU primitives, block-compressed and naive
// isosurfaces, and a streamed store (first surface, flight stops), each GPU
// result checked against a reference computed elsewhere where one exists.
// Writes benchmarks/results/gpu-<gpu>-<date>.json and .md and prints the
// tables. benchmarks/gpu/README.md says how to run it on a lent GPU (the
// bundle pack.mjs makes) and how to compare two results.
//
//   npm run bench:gpu [-- --smoke] [--max-seconds S] [--only probe,zfp,primitives,surfaces,stream,lossless]
//                     [--out DIR] [--data DIR] [--work DIR] [--python PY]
//   npm run bench:gpu -- --compare A.json B.json
import { existsSync, mkdirSync } from 'node:fs';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { describeAdapter, type GpuFailure } from '../../src/gpu/device.ts';
import { requestNodeGpu } from '../../src/gpu/node-gpu.ts';
import { BenchRun, FULL_PLAN, SMOKE_PLAN } from './context.ts';
import { primitivesSection } from './primitives.ts';
import { chromiumAvailability, type ProbeData, probeSection } from './probe.ts';
import { compareRecords, gpuSlug, printRecord, type GpuBenchRecord, writeRecord } from './report.ts';
import { losslessSection } from './lossless.ts';
import { streamSection } from './stream.ts';
import { surfacesSection } from './surfaces.ts';
import { zfpDecodeSection } from './zfp-decode.ts';

const SECTIONS = ['probe', 'zfp', 'primitives', 'surfaces', 'stream', 'lossless'] as const;

function parseArgs(argv: string[]) {
  const opts: Record<string, string | boolean> = {};
  const rest: string[] = [];
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i];
    if (a === '--smoke' || a === '--help') opts[a.slice(2)] = true;
    else if (a.startsWith('--')) {
      if (i + 1 >= argv.length) throw new Error(`${a} needs a value`);
      opts[a.slice(2)] = argv[++i];
    } else rest.push(a);
  }
  return { opts, rest };
}

/** The checkout: the folder above this file (or above the bundle) that holds converter/zfpzarr. */
function findRoot(): string {
  for (let d = dirname(fileURLToPath(import.meta.url)); ; d = dirname(d)) {
    if (existsSync(join(d, 'converter', 'zfpzarr'))) return d;
    if (dirname(d) === d) return process.cwd();
  }
}

async function main(): Promise<number> {
  const { opts, rest } = parseArgs(process.argv.slice(2));
  if (opts.help) {
    console.log(
      'npm run bench:gpu [-- --smoke] [--max-seconds S] [--only probe,zfp,primitives,surfaces,stream,lossless] [--out DIR] [--data DIR] [--work DIR] [--python PY]\n' +
        'npm run bench:gpu -- --compare A.json B.json\nbenchmarks/gpu/README.md: what it measures, and how to run it on a lent GPU.',
    );
    return 0;
  }
  if (typeof opts.compare === 'string') {
    if (rest.length !== 1) throw new Error('--compare A.json B.json');
    compareRecords(opts.compare, rest[0]);
    return 0;
  }
  const root = findRoot();
  const smoke = opts.smoke === true;
  const plan = smoke ? SMOKE_PLAN : FULL_PLAN;
  const data = resolve(
    typeof opts.data === 'string'
      ? opts.data
      : ([join(root, '..', 'shared', 'data'), join(root, '.gpu-bundle', 'data')].find((d) => existsSync(join(d, 'reference', 'mc.json'))) ??
          join(root, '..', 'shared', 'data')),
  );
  const work = resolve(typeof opts.work === 'string' ? opts.work : join(root, '.cache', 'bench-gpu'));
  mkdirSync(work, { recursive: true });
  const venv = join(root, '.venv-converter', 'bin', 'python');
  const python = typeof opts.python === 'string' ? opts.python : (process.env.ZFPISO_PYTHON ?? (existsSync(venv) ? venv : 'python3'));
  const out = resolve(typeof opts.out === 'string' ? opts.out : join(root, 'benchmarks', 'results'));
  mkdirSync(out, { recursive: true });
  const only = typeof opts.only === 'string' ? opts.only.split(',') : [...SECTIONS];
  for (const s of only)
    if (!(SECTIONS as readonly string[]).includes(s)) throw new Error(`--only: unknown section ${s} (${SECTIONS.join(', ')})`);
  const maxSeconds = Number(opts['max-seconds'] ?? (smoke ? 110 : 480));

  // GPU timestamps as the GPU counts them: Dawn rounds them to 65.5 microseconds by default
  process.env.ZFPISO_DAWN_FLAGS ??= 'disable-dawn-features=timestamp_quantization';
  const failures: GpuFailure[] = [];
  const gpu = await requestNodeGpu({ label: 'bench.gpu', onFailure: (f) => failures.push(f) });
  console.log(`bench:gpu${smoke ? ' --smoke' : ''} on ${describeAdapter(gpu.adapter)}; data ${data}; at most ${maxSeconds} s`);
  const run = new BenchRun(gpu, plan, { root, data, work, python }, maxSeconds);
  let probe: ProbeData | undefined;
  // rough seconds each section needs on a GPU (a smoke run on SwiftShader takes about as long)
  if (only.includes('probe'))
    await run.section('probe', 5, async () => {
      probe = await probeSection(run);
      return probe;
    });
  if (only.includes('zfp')) await run.section('zfp decode', 20, () => zfpDecodeSection(run));
  if (only.includes('primitives')) await run.section('primitives', 20, () => primitivesSection(run));
  if (only.includes('surfaces')) await run.section('surfaces', 60, () => surfacesSection(run));
  if (only.includes('stream')) await run.section('stream', 60, () => streamSection(run));
  if (only.includes('lossless')) await run.section('lossless', 30, () => losslessSection(run));
  const chromium = chromiumAvailability();
  run.sections.push({ name: 'page benchmark (Chromium)', status: 'skipped', reason: chromium.reason, seconds: 0 });
  for (const f of failures) run.check('webgpu', 'no uncaptured WebGPU error or device loss', false, `${f.kind}: ${f.message}`);
  if (failures.length === 0) run.check('webgpu', 'no uncaptured WebGPU error or device loss', true, 'none reported');

  const record: GpuBenchRecord = {
    benchmark: 'bench:gpu',
    date: new Date().toISOString(),
    smoke,
    gpu: gpuSlug(run, probe?.nvidiaSmi),
    adapter: probe?.adapter ?? gpu.adapter,
    node: process.version,
    wallSeconds: run.elapsedSeconds,
    maxSeconds,
    sections: run.sections,
    figures: run.figures,
    checks: run.checks,
    tables: run.tables,
    notes: run.notes,
  };
  printRecord(record);
  const base = writeRecord(out, record);
  console.log(`\nwrote ${base}.json and ${base}.md (${run.elapsedSeconds.toFixed(0)} s)`);
  gpu.device.destroy();
  const bad = run.checks.some((c) => !c.ok) || run.sections.some((s) => s.status === 'failed');
  return bad ? 1 : 0;
}

main().then(
  (code) => process.exit(code),
  (e) => {
    console.error(`bench:gpu: ${(e as Error).stack ?? e}`);
    process.exit(2);
  },
);
