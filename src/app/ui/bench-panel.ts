// The in-page benchmark (the paper's section 4.6): random, sweep-up and
// sweep-down sequences of isovalues over a chosen range, seeded, each from an
// empty cache, the first of each left out of the summary. Progress while it
// runs; a summary table, a chart, and the records as JSON or CSV. The same
// harness (src/bench/harness.ts) runs headless in `cli bench`. When the page
// draws rays, the engine also draws (and times) one frame after each surface:
// the table then has the frame and the image (surface + frame) times.

import { recordsToCsv, runBenchmark, type BenchResult, type BenchSummary, type SurfaceEngine } from '../../bench/harness.ts';
import { BENCH_MODES, isBenchMode, type BenchMode } from '../../bench/sequences.ts';
import { byId, download, el } from '../dom.ts';
import { formatCount, formatMs, formatPercent } from '../format.ts';
import { drawBenchChart, MODE_COLORS } from './bench-chart.ts';

export interface BenchContext {
  engine: SurfaceEngine;
  /** Volume description written into the JSON. */
  volume: Record<string, unknown>;
  adapter: Record<string, unknown>;
  baseName: string;
  valueRange: [number, number];
  /** How the frames the engine draws (engine.draw) show the surface, written into the JSON. */
  draw?: 'rays' | 'mesh';
}

export interface BenchPanelHooks {
  /** The volume to benchmark, or undefined when none is loaded. */
  context: () => BenchContext | undefined;
  /** Before the first surface / after the last: lock and unlock the rest of the page. */
  onRunning: (running: boolean) => void;
  /** After each surface (to draw it). */
  onSurface: (iso: number) => void;
  onDone: (result: BenchResult & Record<string, unknown>) => void;
  onError: (message: string) => void;
}

export class BenchPanel {
  private running = false;
  private cancelRequested = false;
  private last: (BenchResult & Record<string, unknown>) | undefined;
  private readonly run = byId<HTMLButtonElement>('bench-run');
  private readonly cancel = byId<HTMLButtonElement>('bench-cancel');
  private readonly status = byId('bench-status');
  private readonly progress = byId('bench-progress');
  private readonly results = byId('bench-results');
  private readonly table = byId<HTMLTableElement>('bench-table');
  private readonly chart = byId<HTMLCanvasElement>('bench-chart');
  private readonly lo = byId<HTMLInputElement>('bench-lo');
  private readonly hi = byId<HTMLInputElement>('bench-hi');
  private readonly count = byId<HTMLInputElement>('bench-count');
  private readonly seed = byId<HTMLInputElement>('bench-seed');

  constructor(private readonly hooks: BenchPanelHooks) {
    this.run.addEventListener('click', () => void this.start());
    this.cancel.addEventListener('click', () => {
      this.cancelRequested = true;
      this.status.textContent = 'Cancelling after the current surface…';
    });
    byId('bench-json').addEventListener('click', () => {
      if (this.last)
        download(
          new Blob([JSON.stringify(this.last, null, 2)], { type: 'application/json' }),
          `${this.last.baseName as string}_bench.json`,
        );
    });
    byId('bench-csv').addEventListener('click', () => {
      if (this.last)
        download(new Blob([recordsToCsv(this.last.records)], { type: 'text/csv' }), `${this.last.baseName as string}_bench.csv`);
    });
  }

  get isRunning(): boolean {
    return this.running;
  }

  get result(): (BenchResult & Record<string, unknown>) | undefined {
    return this.last;
  }

  /**
   * A new volume: the default range is the middle 80 % of its values, as in
   * `cli bench` (the paper leaves out noise and nearly empty surfaces).
   */
  setVolume(valueRange: [number, number] | undefined): void {
    this.run.disabled = !valueRange;
    if (!valueRange) return;
    const [lo, hi] = valueRange;
    this.lo.value = String(Number((lo + 0.1 * (hi - lo)).toPrecision(6)));
    this.hi.value = String(Number((hi - 0.1 * (hi - lo)).toPrecision(6)));
  }

  private modes(): BenchMode[] {
    return [...document.querySelectorAll<HTMLInputElement>('#bench-section input[name="mode"]')]
      .filter((i) => i.checked)
      .map((i) => i.value)
      .filter(isBenchMode);
  }

  private async start(): Promise<void> {
    if (this.running) return;
    const ctx = this.hooks.context();
    if (!ctx) return;
    const modes = this.modes();
    const count = Math.round(this.count.valueAsNumber);
    const seed = Math.round(this.seed.valueAsNumber);
    const lo = this.lo.valueAsNumber;
    const hi = this.hi.valueAsNumber;
    const problem =
      modes.length === 0
        ? 'Choose at least one sequence.'
        : !(count >= 2)
          ? 'Use at least 2 isovalues per sequence.'
          : !Number.isFinite(seed)
            ? 'The seed must be a whole number.'
            : !(Number.isFinite(lo) && Number.isFinite(hi) && hi > lo)
              ? 'The range needs From < To.'
              : undefined;
    if (problem) {
      this.status.textContent = problem;
      return;
    }
    this.running = true;
    this.cancelRequested = false;
    this.run.disabled = true;
    this.cancel.hidden = false;
    this.progress.hidden = false;
    const fill = this.progress.firstElementChild as HTMLElement;
    fill.style.width = '0%';
    this.hooks.onRunning(true);
    const started = new Date();
    try {
      const result = await runBenchmark(ctx.engine, {
        modes,
        count,
        range: [lo, hi],
        seed,
        cancelled: () => this.cancelRequested,
        onProgress: (done, total, r) => {
          fill.style.width = `${((done / total) * 100).toFixed(1)}%`;
          this.status.textContent = `${r.mode} ${r.index + 1}/${count} · ${formatMs(r.gpuMs)}${r.frameMs === undefined ? '' : ` + frame ${formatMs(r.frameMs)}`} · hit ${formatPercent(r.hitRate)}`;
          this.hooks.onSurface(r.iso);
        },
      });
      const full = {
        tool: 'zfp-isosurface-webgpu page benchmark',
        date: started.toISOString(),
        baseName: ctx.baseName,
        volume: ctx.volume,
        adapter: ctx.adapter,
        ...(ctx.engine.draw && ctx.draw ? { draw: ctx.draw } : {}),
        ...result,
      };
      this.last = full;
      this.show(full.summaries, full.records, modes, count);
      this.status.textContent = this.cancelRequested
        ? `Cancelled after ${result.records.length} surfaces.`
        : `Done: ${result.records.length} surfaces.`;
      this.hooks.onDone(full);
    } catch (e) {
      this.status.textContent = 'The benchmark failed.';
      this.hooks.onError(`Benchmark: ${(e as Error).message}`);
    } finally {
      this.running = false;
      this.run.disabled = false;
      this.cancel.hidden = true;
      this.progress.hidden = true;
      this.hooks.onRunning(false);
    }
  }

  private show(summaries: BenchSummary[], records: BenchResult['records'], modes: BenchMode[], count: number): void {
    this.results.hidden = false;
    const rows: [string, (s: BenchSummary) => string][] = [
      ['surfaces', (s) => String(s.count)],
      ['mean GPU', (s) => formatMs(s.meanMs)],
      ['median GPU', (s) => formatMs(s.medianMs)],
      ['mean wall', (s) => formatMs(s.meanWallMs)],
      // frames timed (the page draws rays): a frame per surface, and the time per image (surface + frame)
      ...(summaries.some((s) => s.meanFrameMs !== undefined)
        ? ([
            ['mean frame', (s) => formatMs(s.meanFrameMs ?? Number.NaN)],
            ['median frame', (s) => formatMs(s.medianFrameMs ?? Number.NaN)],
            ['mean image', (s) => formatMs(s.meanImageMs ?? Number.NaN)],
            ['median image', (s) => formatMs(s.medianImageMs ?? Number.NaN)],
          ] as [string, (s: BenchSummary) => string][])
        : []),
      ['hit rate', (s) => formatPercent(s.meanHitRate)],
      ['active', (s) => formatCount(s.meanActiveBlocks)],
      ['new', (s) => formatCount(s.meanNewBlocks)],
      ['occupied', (s) => formatCount(s.meanOccupiedBlocks)],
      ['triangles', (s) => formatCount(s.meanTriangles)],
    ];
    const head = el(
      'tr',
      {},
      el('th', { textContent: 'mean over' }),
      ...summaries.map((s) => {
        const th = el('th', { textContent: s.mode });
        th.style.color = MODE_COLORS[s.mode];
        return th;
      }),
    );
    this.table.replaceChildren(
      el('thead', {}, head),
      el(
        'tbody',
        {},
        ...rows.map(([name, f]) => el('tr', {}, el('th', { textContent: name }), ...summaries.map((s) => el('td', { textContent: f(s) })))),
      ),
    );
    drawBenchChart(
      this.chart,
      records,
      modes.filter((m) => BENCH_MODES.includes(m)),
      count,
    );
  }
}
