// The benchmark chart: GPU time per isovalue (solid, left axis) and cache hit
// rate (dashed, right axis, 0-100 %) for each sequence, by isovalue index.
// The first isovalue of each sequence (left out of the summary) is hollow.

import type { BenchRecord } from '../../bench/harness.ts';
import type { BenchMode } from '../../bench/sequences.ts';

export const MODE_COLORS: Record<BenchMode, string> = {
  random: '#6cb4ff',
  'sweep-up': '#7ddc8f',
  'sweep-down': '#ffb86b',
};

function niceMax(x: number): number {
  if (!(x > 0)) return 1;
  const p = 10 ** Math.floor(Math.log10(x));
  for (const m of [1, 2, 2.5, 5, 10]) if (m * p >= x) return m * p;
  return 10 * p;
}

export function drawBenchChart(canvas: HTMLCanvasElement, records: BenchRecord[], modes: BenchMode[], count: number): void {
  const dpr = window.devicePixelRatio || 1;
  const cssW = canvas.clientWidth || 290;
  const cssH = canvas.clientHeight || 170;
  canvas.width = Math.round(cssW * dpr);
  canvas.height = Math.round(cssH * dpr);
  const g = canvas.getContext('2d');
  if (!g) return;
  g.setTransform(dpr, 0, 0, dpr, 0, 0);
  g.clearRect(0, 0, cssW, cssH);
  const left = 34, right = 30, top = 16, bottom = 20;
  const w = cssW - left - right;
  const h = cssH - top - bottom;
  const maxMs = niceMax(Math.max(0, ...records.map((r) => r.gpuMs)));
  const x = (i: number) => left + (count > 1 ? (i / (count - 1)) * w : w / 2);
  const yMs = (ms: number) => top + h - (ms / maxMs) * h;
  const yHit = (f: number) => top + h - f * h;

  g.font = '10px system-ui, sans-serif';
  g.strokeStyle = '#30343c';
  g.fillStyle = '#8d95a1';
  g.lineWidth = 1;
  for (let k = 0; k <= 4; k++) {
    const yy = Math.round(top + (k / 4) * h) + 0.5;
    g.beginPath();
    g.moveTo(left, yy);
    g.lineTo(left + w, yy);
    g.stroke();
    g.textAlign = 'right';
    g.fillText(String(Number((maxMs * (1 - k / 4)).toPrecision(3))), left - 4, yy + 3);
    g.textAlign = 'left';
    g.fillText(`${100 - k * 25}%`, left + w + 4, yy + 3);
  }
  g.textAlign = 'left';
  g.fillText('GPU ms', 2, 10);
  g.textAlign = 'right';
  g.fillText('hit rate', cssW - 2, 10);
  g.textAlign = 'center';
  g.fillText('isovalue #', left + w / 2, cssH - 4);

  for (const mode of modes) {
    const rs = records.filter((r) => r.mode === mode);
    if (rs.length === 0) continue;
    const color = MODE_COLORS[mode];
    g.strokeStyle = color;
    g.lineWidth = 1.4;
    g.setLineDash([]);
    g.beginPath();
    rs.forEach((r, i) => (i === 0 ? g.moveTo(x(r.index), yMs(r.gpuMs)) : g.lineTo(x(r.index), yMs(r.gpuMs))));
    g.stroke();
    g.setLineDash([3, 3]);
    g.lineWidth = 1;
    g.beginPath();
    rs.forEach((r, i) => (i === 0 ? g.moveTo(x(r.index), yHit(r.hitRate)) : g.lineTo(x(r.index), yHit(r.hitRate))));
    g.stroke();
    g.setLineDash([]);
    const first = rs.find((r) => r.discarded);
    if (first) {
      g.beginPath();
      g.arc(x(first.index), yMs(first.gpuMs), 3, 0, Math.PI * 2);
      g.fillStyle = '#1f2228';
      g.fill();
      g.stroke();
    }
  }
}
