// The converter's suite for `npm test`: pytest in converter/ with the
// converter's own environment. Counts come from pytest's JUnit report.
import { spawnSync } from 'node:child_process';
import { existsSync, readFileSync, rmSync } from 'node:fs';
import { join } from 'node:path';
import { converterEnv, converterPython } from './setup/converter-env.mjs';

export function runConverterTests(root, results, extra = []) {
  const report = join(results, 'converter-pytest.xml');
  rmSync(report, { force: true });
  const args = ['-m', 'pytest', '-q', '-p', 'no:cacheprovider', `--junitxml=${report}`, ...extra];
  console.log(`\n$ (converter) python ${args.join(' ')}`);
  const started = Date.now();
  const r = spawnSync(converterPython(root), args, { cwd: join(root, 'converter'), stdio: 'inherit', env: converterEnv(root) });
  console.log(`converter suite: ${((Date.now() - started) / 1000).toFixed(0)} s`);
  if (!existsSync(report)) return { passed: 0, failed: 1, note: `pytest exited with ${r.status} and wrote no report` };
  const xml = readFileSync(report, 'utf8');
  const head = /<testsuite\b[^>]*>/.exec(xml)?.[0] ?? '';
  const count = (name) => Number(new RegExp(`\\b${name}="(\\d+)"`).exec(head)?.[1] ?? 0);
  const failed = count('failures') + count('errors');
  const passed = count('tests') - failed - count('skipped');
  // pytest exiting non-zero with nothing failed (collection error, crash) fails the suite
  // seconds per test module (classname "tests.test_x.Class" or "tests.test_x")
  const perFile = new Map();
  for (const m of xml.matchAll(/<testcase\b[^>]*\bclassname="([^"]*)"[^>]*\btime="([\d.]+)"/g)) {
    const module = m[1]
      .split('.')
      .filter((p) => !/^[A-Z]/.test(p))
      .join('/');
    const file = `converter/${module}.py`;
    perFile.set(file, (perFile.get(file) ?? 0) + Number(m[2]));
  }
  const files = [...perFile].map(([file, seconds]) => ({ file, seconds }));
  return { passed, failed: failed + (r.status !== 0 && failed === 0 ? 1 : 0), files };
}
