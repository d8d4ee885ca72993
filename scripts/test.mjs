#!/usr/bin/env node
// `npm test`: installs what the tests need (npm packages, Debian's Chromium,
// the Python reference tools), then runs every suite: type check, unit tests
// (vitest on Dawn), the Wasm module checks, the Python converter (pytest),
// and page tests (Playwright in headless Chromium). The last line is `N passed, N failed` over all suites.
//
// `npm test -- unit` / `-- converter` / `-- e2e` / `-- typecheck` runs only those suites; other
// arguments after a suite name go to its runner (e.g. `npm test -- unit tests/unit/zfp`).
import { spawnSync } from 'node:child_process';
import { existsSync, mkdirSync, readFileSync, rmSync } from 'node:fs';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { ensureNodeModules } from './setup/npm-deps.mjs';
import { ensurePythonEnv } from './setup/python-env.mjs';
import { ensureConverterEnv } from './setup/converter-env.mjs';
import { runConverterTests } from './converter-tests.mjs';
import { ensureSystemPackages } from './setup/system-deps.mjs';

const root = fileURLToPath(new URL('..', import.meta.url));
const results = join(root, 'test-results');
const SUITES = ['typecheck', 'unit', 'converter', 'e2e'];

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

function unit(extra) {
  const out = join(results, 'vitest.json');
  rmSync(out, { force: true });
  const status = run(npx('vitest'), ['run', '--reporter=default', '--reporter=json', `--outputFile.json=${out}`, ...extra]);
  const report = readJson(out);
  if (!report) return { passed: 0, failed: 1, note: `vitest exited with ${status} and wrote no report` };
  // A crashed worker or an error outside tests fails the suite even if every test passed.
  const extraFail = status !== 0 && report.numFailedTests === 0 ? 1 : 0;
  return { passed: report.numPassedTests, failed: report.numFailedTests + extraFail };
}

function e2e(extra) {
  const out = join(results, 'playwright.json');
  rmSync(out, { force: true });
  const status = run(npx('playwright'), ['test', '--reporter=list,json', ...extra], { PLAYWRIGHT_JSON_OUTPUT_NAME: out });
  const report = readJson(out);
  if (!report?.stats) return { passed: 0, failed: 1, note: `playwright exited with ${status} and wrote no report` };
  const { expected = 0, unexpected = 0, flaky = 0 } = report.stats;
  const extraFail = status !== 0 && unexpected === 0 ? 1 : 0;
  return { passed: expected + flaky, failed: unexpected + extraFail };
}

function main() {
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
  for (const suite of chosen) {
    const r = suite === 'typecheck' ? typecheck() : suite === 'unit' ? unit(extra) : suite === 'converter' ? runConverterTests(root, results, extra) : e2e(extra);
    totals.passed += r.passed;
    totals.failed += r.failed;
    lines.push(`${suite.padEnd(10)} ${r.passed} passed, ${r.failed} failed${r.note ? ` (${r.note})` : ''}`);
  }
  console.log('\nsummary');
  for (const l of lines) console.log(`  ${l}`);
  console.log(`\n${totals.passed} passed, ${totals.failed} failed`);
  process.exit(totals.failed > 0 ? 1 : 0);
}

if (!existsSync(join(root, 'package.json'))) throw new Error('run from the repository');
main();
