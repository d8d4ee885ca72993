#!/usr/bin/env node
// `npm test`: installs what the tests need (npm packages, Debian's Chromium,
// the Python reference tools, the converter's environment, Deno), then runs
// every suite: type check, unit tests (vitest on Dawn), `limits` (the zfp and
// isosurface GPU tests again on a device with WebGPU's default limits),
// `gpukernels` (the surface tests again with the GPU-shaped scans, compactions
// and zfp decode forced, the kernels a real GPU gets), `wgpu`
// (the GPU unit tests on wgpu in Deno: scripts/test-wgpu.mjs), `converter`
// (the Python converter's pytest suite), and page tests (Playwright in headless
// Chromium, with the flag set probed by scripts/setup/chromium-flags.mjs).
// The last line is `N passed, N failed` over all suites.
//
// `npm test -- unit` / `-- limits` / `-- gpukernels` / `-- wgpu` / `-- converter` / `-- e2e` / `-- typecheck` runs only
// that suite; other arguments after a suite name go to its runner (e.g. `npm test -- unit tests/unit/zfp`).
import { spawnSync } from 'node:child_process';
import { existsSync, mkdirSync, readFileSync, rmSync } from 'node:fs';
import { join, relative } from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromiumWebGpuLaunch } from './setup/chromium-flags.mjs';
import { ensureNodeModules } from './setup/npm-deps.mjs';
import { ensurePythonEnv } from './setup/python-env.mjs';
import { ensureConverterEnv } from './setup/converter-env.mjs';
import { runConverterTests } from './converter-tests.mjs';
import { ensureSystemPackages } from './setup/system-deps.mjs';
import { runWgpuTests } from './test-wgpu.mjs';

const root = fileURLToPath(new URL('..', import.meta.url));
const results = join(root, 'test-results');
const SUITES = ['typecheck', 'unit', 'limits', 'gpukernels', 'wgpu', 'converter', 'e2e'];
// The `limits` suite: the GPU tests of these folders again on a device with
// WebGPU's default limits (tests/helpers/gpu.ts), so sharding and fallbacks run.
const LIMITS_TESTS = [
  'tests/unit/zfp/decoder.test.ts',
  'tests/unit/zfp/decode-volume.test.ts',
  'tests/unit/zfp/encoder.test.ts',
  'tests/unit/zfp/offsets.test.ts',
  'tests/unit/isosurface/',
  'tests/unit/store/chunked-volume.test.ts',
  // the stream controller's surfaces over chunk pools
  'tests/unit/store/stream-gpu.test.ts',
  // chunk roles (drawn, ghost, idle): the view cut's surfaces restricted to some chunks of a pool
  'tests/unit/store/chunk-roles.test.ts',
];
const LIMITS_EXCLUDE = ['tests/unit/isosurface/cli.test.ts'];
// The `gpukernels` suite: on SwiftShader every kernel family is chosen as the
// emulator path (src/primitives/README.md), so these surface tests run again
// with the GPU path forced (ZFPISO_KERNEL_PATH=gpu: workgroup-memory and
// subgroup scans, tiled compaction, tiled zfp decode) against VTK and the CPU
// models. The unit tests of the primitives and the decoder cover both paths
// on their own.
const GPU_KERNEL_TESTS = [
  'tests/unit/isosurface/vtk.test.ts',
  'tests/unit/isosurface/vtk-bonsai.test.ts',
  'tests/unit/isosurface/block-mc.test.ts',
  'tests/unit/isosurface/lru-cache.test.ts',
  'tests/unit/isosurface/pipeline.test.ts',
  'tests/unit/store/chunk-roles.test.ts',
];

function run(cmd, args, env = {}) {
  console.log(`\n$ ${cmd} ${args.join(' ')}`);
  const r = spawnSync(cmd, args, { cwd: root, stdio: 'inherit', env: { ...process.env, ...env } });
  return r.status ?? 1;
}

function readJson(path) {
  try {
    return JSON.parse(readFileSync(path, 'utf8'));
  } catch {
    return undefined;
  }
}

const npx = (bin) => join(root, 'node_modules', '.bin', bin);

function typecheck() {
  const status = run(npx('tsc'), ['--noEmit', '-p', 'tsconfig.json']);
  return { passed: status === 0 ? 1 : 0, failed: status === 0 ? 0 : 1 };
}

function unit(extra, { reportName = 'vitest.json', env = {} } = {}) {
  const out = join(results, reportName);
  rmSync(out, { force: true });
  const status = run(npx('vitest'), ['run', '--reporter=default', '--reporter=json', `--outputFile.json=${out}`, ...extra], env);
  const report = readJson(out);
  if (!report) return { passed: 0, failed: 1, note: `vitest exited with ${status} and wrote no report` };
  // A crashed worker or an error outside tests fails the suite even if every test passed.
  const extraFail = status !== 0 && report.numFailedTests === 0 ? 1 : 0;
  const files = (report.testResults ?? []).map((t) => ({ file: relative(root, t.name), seconds: (t.endTime - t.startTime) / 1000 }));
  return { passed: report.numPassedTests, failed: report.numFailedTests + extraFail, files };
}

function limits(extra) {
  const files = extra.length > 0 ? extra : [...LIMITS_TESTS, ...LIMITS_EXCLUDE.map((f) => `--exclude=${f}`)];
  return unit(files, { reportName: 'vitest-default-limits.json', env: { ZFPISO_TEST_LIMITS: 'default' } });
}

function gpuKernels(extra) {
  return unit(extra.length > 0 ? extra : GPU_KERNEL_TESTS, { reportName: 'vitest-gpu-kernels.json', env: { ZFPISO_KERNEL_PATH: 'gpu' } });
}

async function wgpu(extra) {
  try {
    return await runWgpuTests(extra.length > 0 ? extra.map((f) => join(root, f)) : undefined);
  } catch (e) {
    console.error(`\n[wgpu] ${e.message}`);
    return { passed: 0, failed: 1, note: e.message.split('\n')[0] };
  }
}

async function e2e(extra) {
  // The flag set that draws a WebGPU canvas here (probed once, then cached).
  try {
    const launch = await chromiumWebGpuLaunch();
    console.log(
      `\nChromium flags: ${launch.name} (${launch.chromium}): ${launch.args.join(' ')}${Object.entries(launch.env)
        .map(([k, v]) => ` ${k}=${v}`)
        .join('')}`,
    );
  } catch (e) {
    console.error(`\n[setup] ${e.message}`);
    return { passed: 0, failed: 1, note: 'no Chromium flag set draws a WebGPU canvas' };
  }
  const out = join(results, 'playwright.json');
  rmSync(out, { force: true });
  const status = run(npx('playwright'), ['test', '--reporter=list,json', ...extra], { PLAYWRIGHT_JSON_OUTPUT_NAME: out });
  const report = readJson(out);
  if (!report?.stats) return { passed: 0, failed: 1, note: `playwright exited with ${status} and wrote no report` };
  const { expected = 0, unexpected = 0, flaky = 0 } = report.stats;
  const extraFail = status !== 0 && unexpected === 0 ? 1 : 0;
  // per spec file: the sum of its tests' run times (retries included)
  const perFile = new Map();
  const walk = (suite) => {
    for (const spec of suite.specs ?? [])
      for (const t of spec.tests ?? [])
        for (const r of t.results ?? []) perFile.set(suite.file, (perFile.get(suite.file) ?? 0) + (r.duration ?? 0) / 1000);
    for (const child of suite.suites ?? []) walk({ ...child, file: child.file ?? suite.file });
  };
  for (const suite of report.suites ?? []) walk(suite);
  const files = [...perFile].map(([file, seconds]) => ({ file: join('tests/e2e', file), seconds }));
  return { passed: expected + flaky, failed: unexpected + extraFail, files };
}

async function main() {
  const args = process.argv.slice(2);
  const chosen = args.length > 0 && SUITES.includes(args[0]) ? [args[0]] : SUITES;
  const extra = args.length > 0 && SUITES.includes(args[0]) ? args.slice(1) : [];
  mkdirSync(results, { recursive: true });

  let setupError;
  try {
    ensureNodeModules(root);
    ensureSystemPackages();
    ensurePythonEnv(root);
    ensureConverterEnv(root);
  } catch (e) {
    setupError = e;
  }
  if (setupError) {
    console.error(`\n[setup] ${setupError.message}`);
    console.log('\n0 passed, 1 failed');
    process.exit(1);
  }

  const totals = { passed: 0, failed: 0 };
  const lines = [];
  const fileTimes = [];
  for (const suite of chosen) {
    const started = Date.now();
    const r =
      suite === 'typecheck'
        ? typecheck()
        : suite === 'unit'
          ? unit(extra)
          : suite === 'limits'
            ? limits(extra)
            : suite === 'gpukernels'
              ? gpuKernels(extra)
              : suite === 'wgpu'
                ? await wgpu(extra)
                : suite === 'converter'
                  ? runConverterTests(root, results, extra)
                  : await e2e(extra);
    totals.passed += r.passed;
    totals.failed += r.failed;
    for (const f of r.files ?? []) fileTimes.push({ ...f, suite });
    const minutes = ((Date.now() - started) / 60_000).toFixed(1);
    lines.push(`${suite.padEnd(10)} ${r.passed} passed, ${r.failed} failed${r.note ? ` (${r.note})` : ''}, ${minutes} min`);
  }
  console.log('\nsummary (minutes per suite)');
  for (const l of lines) console.log(`  ${l}`);
  if (fileTimes.length > 0) {
    // files run side by side in a suite: their times add up to more than the suite's wall time
    console.log('\nthe ten slowest files (seconds; vitest files run two at a time)');
    for (const f of fileTimes.sort((a, b) => b.seconds - a.seconds).slice(0, 10))
      console.log(`  ${f.seconds.toFixed(0).padStart(5)}  ${f.suite.padEnd(10)} ${f.file}`);
  }
  console.log(`\n${totals.passed} passed, ${totals.failed} failed`);
  process.exit(totals.failed > 0 ? 1 : 0);
}

if (!existsSync(join(root, 'package.json'))) throw new Error('run from the repository');
await main();
