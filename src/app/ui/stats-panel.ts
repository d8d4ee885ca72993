// The numbers a user reads about the volume and the current surface: sizes
// and rate, blocks (total / active / occupied), the cache (slots, memory,
// newly decompressed blocks, hit rate), triangles and vertex memory, GPU time
// per stage, frame rate.

import { INDEX_BYTES, VERTEX_BYTES } from '../../isosurface/layout.ts';
import type { IsosurfaceStats } from '../../isosurface/types.ts';
import type { OpenedVolume } from '../../volume/open-volume.ts';
import { setInfoList } from '../info-list.ts';
import { formatBytes, formatCount, formatMs, formatPercent } from '../format.ts';
import { el } from '../dom.ts';

export function volumeRows(v: Omit<OpenedVolume, 'stream'>, blockCount: number, valueRange: [number, number]): [string, string][] {
  const [nx, ny, nz] = v.dims;
  const decoded = nx * ny * nz * 4;
  const source =
    v.kind === 'default'
      ? 'generated, compressed on the GPU'
      : v.compressedHere
        ? `${v.sourceDtype} ${v.kind === 'nrrd' ? 'NRRD' : v.kind === 'tiff' ? 'TIFF' : 'raw'}, compressed on the GPU`
        : v.kind === 'zfp'
          ? 'zfp stream with header'
          : 'header-less zfp stream';
  return [
    ['name', v.name],
    ['dims', `${nx} × ${ny} × ${nz}`],
    ['source', source],
    ['rate', rateText(v)],
    ...(v.rateChoice?.stream
      ? [
          ['error', `RMS ${fmtError(v.rateChoice.stream.rms)}, max ${fmtError(v.rateChoice.stream.maxAbs)} (decoded − source)`] as [
            string,
            string,
          ],
        ]
      : []),
    ['compressed', `${formatBytes(v.compressedBytes)} (${(decoded / v.compressedBytes).toFixed(1)} : 1)`],
    ['decompressed', `${formatBytes(decoded)} as float32`],
    ['blocks', `${formatCount(blockCount)} of 4³`],
    ['values', `${valueRange[0].toPrecision(5)} … ${valueRange[1].toPrecision(5)}`],
  ];
}

/** The rate and how it was found (volumes compressed here: chosen from the data, given, or lowered to fit). */
function rateText(v: Omit<OpenedVolume, 'stream'>): string {
  const c = v.rateChoice;
  if (!c) return `${v.rate} bits/value`;
  const bound = `bound ${fmtError(c.bound.rms)}: ${c.bound.rule}`;
  switch (c.how) {
    case 'chosen':
      return `${v.rate} bits/value, chosen from the data (sampled RMS error ${fmtError(c.sample.rms)} ≤ ${bound})`;
    case 'given':
      return `${v.rate} bits/value, as given (sampled RMS error ${fmtError(c.sample.rms)}; ${bound})`;
    case 'capped':
      return `${v.rate} bits/value, lowered from ${c.faithfulRate} to fit the memory budget (sampled RMS error ${fmtError(c.sample.rms)} > ${bound})`;
    case 'unmet':
      return `${v.rate} bits/value (no rate meets the ${bound}; sampled RMS error ${fmtError(c.sample.rms)})`;
  }
}

function fmtError(e: number): string {
  return e === 0 ? '0' : e >= 0.01 && e < 1000 ? String(Number(e.toPrecision(3))) : e.toExponential(2);
}

export class StatsPanel {
  constructor(
    private readonly surface: HTMLElement,
    private readonly memory: HTMLElement,
    private readonly stages: HTMLElement,
    /** The frame-rate text (kept current by the HUD). */
    private readonly fpsText: () => string = () => '–',
  ) {}

  /** Updates only the frame-rate row. */
  setFps(text: string): void {
    const dd = this.surface.querySelector<HTMLElement>('dd[data-key="frame rate"]');
    if (dd) dd.textContent = text;
  }

  clear(): void {
    setInfoList(this.surface, []);
    setInfoList(this.memory, []);
    this.stages.replaceChildren();
  }

  update(s: IsosurfaceStats, blockCount: number, latencyMs: number | undefined): void {
    setInfoList(this.surface, [
      ['isovalue', String(Number(s.isovalue.toPrecision(7)))],
      ['triangles', formatCount(s.triangles)],
      ['vertices', `${formatCount(s.vertices)} (${formatBytes(s.vertices * VERTEX_BYTES)})`],
      ['indices', `${formatCount(s.indices)} (${formatBytes(s.indices * INDEX_BYTES)})`],
      [
        'active blocks',
        `${formatCount(s.activeBlocks)} of ${formatCount(blockCount)} (${formatPercent(s.activeBlocks / Math.max(1, blockCount))})`,
      ],
      ['occupied blocks', formatCount(s.occupiedBlocks)],
      ['decompressed', `${formatCount(s.newBlocks)} new blocks`],
      ['hit rate', formatPercent(s.hitRate)],
      ['GPU time', `${formatMs(s.gpuMs)}${s.timingSource === 'queue-wall-time' ? ' (queue wall time)' : ''}`],
      ['latency', latencyMs === undefined ? '–' : formatMs(latencyMs)],
      ['frame rate', this.fpsText()],
    ]);
    setInfoList(this.memory, [
      ['cache slots', `${formatCount(s.cacheSlotsUsed)} used of ${formatCount(s.cacheSlots)}`],
      ['cache memory', formatBytes(s.cacheBytes)],
      ['vertex buffers', formatBytes(s.vertexBytes)],
      ['budgeted total', formatBytes(s.cacheBytes + s.vertexBytes)],
      ...(s.fixedBytes !== undefined ? ([['stream + ranges', formatBytes(s.fixedBytes)]] as [string, string][]) : []),
    ]);
    this.drawStages(s);
  }

  private drawStages(s: IsosurfaceStats): void {
    const max = Math.max(1e-9, ...s.stages.map((t) => t.ms));
    this.stages.replaceChildren(
      ...s.stages.map((t) => {
        const bar = el('span', { className: 'stage-bar' });
        bar.style.width = `${(t.ms / max) * 100}%`;
        const row = el(
          'div',
          { className: 'stage' },
          el('span', { className: 'stage-name', textContent: t.label, title: t.label }),
          el('span', { className: 'stage-track' }, bar),
          el('span', { className: 'stage-ms', textContent: formatMs(t.ms) }),
        );
        row.dataset.stage = t.label;
        return row;
      }),
    );
  }
}
