// Shared benchmark reporting: repeat a measurement, drop the first run (warm-up,
// pipeline compilation), take the median, print a table, write JSON.
import { mkdirSync, writeFileSync } from 'node:fs';
import { dirname } from 'node:path';
import { summarize, type Stats } from '../../src/bench/stats.ts';

export { summarize, type Stats };

/** Runs `measure` `repeats` times (sequentially); returns the stats of its results. */
export async function repeat(repeats: number, measure: (i: number) => Promise<number> | number): Promise<Stats> {
  const all: number[] = [];
  for (let i = 0; i < repeats; i++) all.push(await measure(i));
  return summarize(all);
}

export type Cell = string | number;

/** Prints an aligned text table (numbers right-aligned). */
export function printTable(title: string, header: string[], rows: Cell[][]): void {
  const text = rows.map((r) => r.map((c) => (typeof c === 'number' ? formatNumber(c) : c)));
  const widths = header.map((h, i) => Math.max(h.length, ...text.map((r) => r[i]?.length ?? 0)));
  const line = (cells: string[], numeric: boolean[]) =>
    cells.map((c, i) => (numeric[i] ? c.padStart(widths[i]) : c.padEnd(widths[i]))).join('  ');
  console.log(`\n${title}`);
  console.log(
    line(
      header,
      header.map(() => false),
    ),
  );
  console.log(widths.map((w) => '-'.repeat(w)).join('  '));
  for (let r = 0; r < rows.length; r++)
    console.log(
      line(
        text[r],
        rows[r].map((c) => typeof c === 'number'),
      ),
    );
}

export function formatNumber(x: number): string {
  if (!Number.isFinite(x)) return String(x);
  if (Number.isInteger(x) && Math.abs(x) < 1e9) return String(x);
  const a = Math.abs(x);
  if (a >= 1e9 || (a > 0 && a < 1e-3)) return x.toExponential(3);
  return x.toPrecision(4);
}

export function writeJson(path: string, data: unknown): void {
  mkdirSync(dirname(path), { recursive: true });
  writeFileSync(path, JSON.stringify(data, null, 2) + '\n');
  console.log(`\nwrote ${path}`);
}
