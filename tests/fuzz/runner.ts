// Runs mutated files through each reader's target (tests/fuzz/target.ts) and
// sorts every case into one outcome:
//   rejected  the reader's own error, naming the file (what a user should see)
//   accepted  opened (a mutation may still be a valid file)
//   crash     any other error: a RangeError/TypeError, a Wasm trap, an error
//             of the right type that does not name the file
//   hang      not settled within the time limit
//   alloc     an allocation above the limit was requested (alloc-guard.ts),
//             or the process grew by more than the limit during the case
// and reports a table per reader (cases, outcomes, slowest case, peak memory).

import { installAllocationGuard, AllocationLimitError } from './alloc-guard.ts';
import { makeCase } from './mutators.ts';
import type { FuzzTarget } from './target.ts';

export type Outcome = 'rejected' | 'accepted' | 'crash' | 'hang' | 'alloc';

export interface FuzzOptions {
  casesPerReader: number;
  runSeed: number;
  /** A case that does not settle within this is a hang. */
  timeLimitMs: number;
  /** A single allocation (or growth of the process) above this is absurd. */
  allocLimitBytes: number;
  /** Called after every case (progress). */
  onCase?: (reader: string, index: number, outcome: Outcome) => void;
}

export interface FuzzProblem {
  reader: string;
  index: number;
  outcome: Outcome;
  seed: string;
  name: string;
  mutation: string;
  bytes: number;
  message: string;
}

export interface ReaderReport {
  reader: string;
  seeds: number;
  cases: number;
  rejected: number;
  accepted: number;
  crashes: number;
  hangs: number;
  allocs: number;
  /** Slowest case, ms. */
  slowestMs: number;
  totalMs: number;
  /** Highest resident set size of the process seen during this reader's cases (sampled every 10 ms and after each case). */
  peakRssBytes: number;
  /** Largest ArrayBuffer memory seen (process.memoryUsage().arrayBuffers). */
  peakArrayBufferBytes: number;
  /** Largest single typed-array/ArrayBuffer request seen by the guard. */
  largestRequestBytes: number;
  /** Rejection messages by frequency (first words), for a look at what users see. */
  topRejections: [string, number][];
  problems: FuzzProblem[];
}

class Hang extends Error {}

function messageOf(e: unknown): string {
  if (e instanceof Error) return `${e.name}: ${e.message}`;
  return String(e);
}

/** Runs `opts.casesPerReader` cases against each target, one after the other. */
export async function runFuzz(targets: readonly FuzzTarget[], opts: FuzzOptions): Promise<ReaderReport[]> {
  const reports: ReaderReport[] = [];
  for (const target of targets) reports.push(await runTarget(target, opts));
  return reports;
}

export async function runTarget(target: FuzzTarget, opts: FuzzOptions): Promise<ReaderReport> {
  const seeds = await target.seeds();
  if (seeds.length === 0) throw new Error(`fuzz target ${target.reader}: no seeds`);
  const report: ReaderReport = {
    reader: target.reader,
    seeds: seeds.length,
    cases: 0,
    rejected: 0,
    accepted: 0,
    crashes: 0,
    hangs: 0,
    allocs: 0,
    slowestMs: 0,
    totalMs: 0,
    peakRssBytes: 0,
    peakArrayBufferBytes: 0,
    largestRequestBytes: 0,
    topRejections: [],
    problems: [],
  };
  const rejections = new Map<string, number>();
  // Largest rise of rss / ArrayBuffer memory above its lowest point so far in the current case
  // (reset before each), so garbage of an earlier case collected meanwhile does not hide an allocation.
  let caseLow = { rss: Infinity, arrayBuffers: Infinity };
  let caseRise = 0;
  const sample = () => {
    const m = process.memoryUsage();
    if (m.rss > report.peakRssBytes) report.peakRssBytes = m.rss;
    if (m.arrayBuffers > report.peakArrayBufferBytes) report.peakArrayBufferBytes = m.arrayBuffers;
    caseLow = { rss: Math.min(caseLow.rss, m.rss), arrayBuffers: Math.min(caseLow.arrayBuffers, m.arrayBuffers) };
    caseRise = Math.max(caseRise, m.rss - caseLow.rss, m.arrayBuffers - caseLow.arrayBuffers);
    return m;
  };
  const sampler = setInterval(sample, 10);
  try {
    for (let i = 0; i < opts.casesPerReader; i++) {
      const c = makeCase(seeds, i, opts.runSeed, target.reader);
      caseLow = { rss: Infinity, arrayBuffers: Infinity };
      caseRise = 0;
      sample();
      const guard = installAllocationGuard(opts.allocLimitBytes);
      const t0 = performance.now();
      let outcome: Outcome;
      let message = '';
      let timer: ReturnType<typeof setTimeout> | undefined;
      try {
        const timeout = new Promise<never>((_, reject) => {
          timer = setTimeout(() => reject(new Hang()), opts.timeLimitMs);
        });
        await Promise.race([Promise.resolve().then(() => target.open(c.name, c.bytes)), timeout]);
        outcome = 'accepted';
      } catch (e) {
        if (e instanceof Hang) {
          outcome = 'hang';
          message = `did not settle within ${opts.timeLimitMs} ms`;
        } else if (e instanceof AllocationLimitError || (e instanceof Error && e.cause instanceof AllocationLimitError)) {
          outcome = 'alloc';
          message = messageOf(e);
        } else if (target.isCleanRejection(e, c.name)) {
          outcome = 'rejected';
          const text = e instanceof Error ? e.message : String(e);
          const key = text
            .split(c.name)
            .join('FILE')
            .replace(/\d+(\.\d+)?/g, 'N')
            .slice(0, 90);
          rejections.set(key, (rejections.get(key) ?? 0) + 1);
        } else {
          outcome = 'crash';
          message = messageOf(e);
        }
      } finally {
        clearTimeout(timer);
        guard.release();
      }
      const ms = performance.now() - t0;
      sample();
      report.largestRequestBytes = Math.max(report.largestRequestBytes, guard.largest);
      const grew = caseRise;
      if (outcome !== 'alloc' && outcome !== 'hang' && grew > opts.allocLimitBytes) {
        outcome = 'alloc';
        message = `the process grew by ${grew} bytes during the case (limit ${opts.allocLimitBytes})${message ? `; ${message}` : ''}`;
      }
      report.cases++;
      report.totalMs += ms;
      report.slowestMs = Math.max(report.slowestMs, ms);
      if (outcome === 'rejected') report.rejected++;
      else if (outcome === 'accepted') report.accepted++;
      else {
        if (outcome === 'crash') report.crashes++;
        else if (outcome === 'hang') report.hangs++;
        else report.allocs++;
        report.problems.push({
          reader: target.reader,
          index: i,
          outcome,
          seed: c.seed,
          name: c.name,
          mutation: c.mutation,
          bytes: c.bytes.length,
          message: message.slice(0, 400),
        });
      }
      opts.onCase?.(target.reader, i, outcome);
    }
  } finally {
    clearInterval(sampler);
  }
  report.topRejections = [...rejections].sort((a, b) => b[1] - a[1]).slice(0, 12);
  return report;
}

const mib = (n: number) => (n >= 2 ** 20 ? `${(n / 2 ** 20).toFixed(0)} MiB` : `${(n / 1024).toFixed(0)} KiB`);

/** The table of issue 13's closing note, one row per reader. */
export function formatFuzzTable(reports: readonly ReaderReport[]): string {
  const head = [
    'reader',
    'cases',
    'clean rejections',
    'accepted',
    'crashes',
    'hangs',
    'allocs > limit',
    'slowest',
    'peak RSS',
    'peak ArrayBuffers',
    'largest request',
  ];
  const rows = reports.map((r) => [
    r.reader,
    String(r.cases),
    String(r.rejected),
    String(r.accepted),
    String(r.crashes),
    String(r.hangs),
    String(r.allocs),
    `${r.slowestMs.toFixed(0)} ms`,
    mib(r.peakRssBytes),
    mib(r.peakArrayBufferBytes),
    mib(r.largestRequestBytes),
  ]);
  const lines = [head, ...rows].map((cells) => `| ${cells.join(' | ')} |`);
  lines.splice(1, 0, `|${head.map(() => '---').join('|')}|`);
  return lines.join('\n');
}
