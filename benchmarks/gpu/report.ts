// bench:gpu's record: one JSON (every figure, check, section, table, note)
// and the same tables as Markdown, named by the GPU; and the comparison of
// two such records, figure by figure.
import { readFileSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { formatNumber, printTable } from '../lib/report.ts';
import type { BenchRun, Check, Figure, Table } from './context.ts';

export interface GpuBenchRecord {
  benchmark: 'bench:gpu';
  date: string;
  smoke: boolean;
  gpu: string;
  adapter: unknown;
  node: string;
  wallSeconds: number;
  maxSeconds: number;
  sections: BenchRun['sections'];
  figures: Figure[];
  checks: Check[];
  tables: Table[];
  notes: string[];
}

/** 'nvidia-h200', 'swiftshader', ...: the file name's GPU part. */
export function gpuSlug(run: BenchRun, smi?: string): string {
  const a = run.gpu.adapter;
  if (a.software) return 'swiftshader';
  const name = smi?.split(',')[0] || a.description || a.device || [a.vendor, a.architecture].filter(Boolean).join(' ') || 'gpu';
  return name
    .toLowerCase()
    .replace(/nvidia\s+/g, 'nvidia ')
    .replace(/[^a-z0-9]+/g, '-')
    .replace(/^-|-$/g, '');
}

export function markdown(r: GpuBenchRecord): string {
  const cell = (c: string | number) => (typeof c === 'number' ? formatNumber(c) : c.replace(/\|/g, '\\|'));
  const lines = [
    `# bench:gpu on ${r.gpu} (${r.date.slice(0, 10)})${r.smoke ? ' — smoke sizes' : ''}`,
    '',
    `Node ${r.node}; ${r.wallSeconds.toFixed(0)} s of a ${r.maxSeconds} s allowance. Checks: ${r.checks.filter((c) => c.ok).length} of ${r.checks.length} passed.`,
    '',
    '| section | status | seconds | note |',
    '|---|---|---|---|',
    ...r.sections.map((s) => `| ${s.name} | ${s.status} | ${s.seconds.toFixed(1)} | ${cell(s.reason ?? '')} |`),
    '',
  ];
  for (const t of r.tables) {
    lines.push(`## ${t.title}`, '', `| ${t.header.join(' | ')} |`, `|${t.header.map(() => '---').join('|')}|`);
    for (const row of t.rows) lines.push(`| ${row.map(cell).join(' | ')} |`);
    lines.push('');
  }
  lines.push('## Checks (GPU results against references computed elsewhere)', '');
  for (const c of r.checks) lines.push(`- ${c.ok ? 'ok' : '**FAILED**'}: ${c.name} — ${c.detail}`);
  if (r.notes.length > 0) lines.push('', '## Notes', '', ...r.notes.map((n) => `- ${n}`));
  return `${lines.join('\n')}\n`;
}

export function writeRecord(dir: string, r: GpuBenchRecord): string {
  const base = join(dir, `gpu-${r.gpu}-${r.date.slice(0, 10)}${r.smoke ? '-smoke' : ''}`);
  writeFileSync(`${base}.json`, `${JSON.stringify(r, null, 1)}\n`);
  writeFileSync(`${base}.md`, markdown(r));
  return base;
}

export function printRecord(r: GpuBenchRecord): void {
  for (const t of r.tables) printTable(t.title, t.header, t.rows);
  console.log(`\nsections: ${r.sections.map((s) => `${s.name} ${s.status}${s.reason ? ` (${s.reason})` : ''}`).join('; ')}`);
  const failed = r.checks.filter((c) => !c.ok);
  console.log(
    `checks: ${r.checks.length - failed.length} of ${r.checks.length} passed${failed.length ? `; FAILED: ${failed.map((c) => c.name).join('; ')}` : ''}`,
  );
  for (const n of r.notes) console.log(`note: ${n}`);
}

/** Two records side by side: every figure of either, B / A where both have it. */
export function compareRecords(pathA: string, pathB: string): void {
  const a = JSON.parse(readFileSync(pathA, 'utf8')) as GpuBenchRecord;
  const b = JSON.parse(readFileSync(pathB, 'utf8')) as GpuBenchRecord;
  const key = (f: Figure) => `${f.section}: ${f.name}`;
  const fa = new Map(a.figures.map((f) => [key(f), f]));
  const fb = new Map(b.figures.map((f) => [key(f), f]));
  const keys = [...new Set([...fa.keys(), ...fb.keys()])];
  printTable(
    `A = ${a.gpu} ${a.date.slice(0, 10)}${a.smoke ? ' (smoke)' : ''}, B = ${b.gpu} ${b.date.slice(0, 10)}${b.smoke ? ' (smoke)' : ''}`,
    ['figure', 'unit', 'A', 'B', 'B / A'],
    keys.map((k) => {
      const x = fa.get(k),
        y = fb.get(k);
      return [k, (x ?? y)!.unit, x?.value ?? '', y?.value ?? '', x && y ? y.value / x.value : ''];
    }),
  );
}
