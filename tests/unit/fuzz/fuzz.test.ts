// The fuzz suite (tests/fuzz/): mutated files through every reader, as the
// page and the CLI open them. Fails on any crash (an error that is not the
// reader's clean rejection naming the file), hang or allocation above the
// limit. CI runs FUZZ_CASES per reader (default 500); longer runs:
//   FUZZ_CASES=2000 npx vitest run tests/unit/fuzz/fuzz.test.ts
// FUZZ_SEED changes the run seed, FUZZ_READERS=zfp,nrrd picks readers. The
// table and the problems go to test-results/fuzz-<cases>.json.
import { mkdirSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { expect, it } from 'vitest';
import { formatFuzzTable, runTarget, type ReaderReport } from '../../fuzz/runner.ts';
import { coreFuzzTargets } from '../../fuzz/targets-core.ts';
import { wasmFuzzTargets } from '../../fuzz/targets-wasm.ts';

const cases = Number(process.env.FUZZ_CASES ?? 500);
const runSeed = Number(process.env.FUZZ_SEED ?? 13);
const only = process.env.FUZZ_READERS?.split(',');
const targets = [...coreFuzzTargets, ...wasmFuzzTargets].filter((t) => !only || only.includes(t.reader));
const reports: ReaderReport[] = [];

for (const target of targets) {
  it(`${target.reader}: ${cases} mutated files, no crash, hang or allocation over 1 GiB`, {
    timeout: Math.max(300_000, cases * 2_000),
  }, async () => {
    const report = await runTarget(target, { casesPerReader: cases, runSeed, timeLimitMs: 20_000, allocLimitBytes: 2 ** 30 });
    reports.push(report);
    const outDir = join(import.meta.dirname, '..', '..', '..', 'test-results');
    mkdirSync(outDir, { recursive: true });
    writeFileSync(
      join(outDir, `fuzz-${cases}.json`),
      JSON.stringify({ cases, runSeed, table: formatFuzzTable(reports), reports }, null, 2) + '\n',
    );
    console.log(`\n${formatFuzzTable([report])}\nrejections: ${report.topRejections.map(([m, n]) => `${n}x ${m}`).join('\n  ')}`);
    const shown = report.problems.slice(0, 8).map((p) => `#${p.index} ${p.outcome} ${p.name} (${p.mutation}): ${p.message}`);
    expect(shown, `${report.problems.length} problems`).toEqual([]);
    expect(report.cases).toBe(cases);
  });
}
