// The benchmark chart, two panels over the isovalue index: GPU time per
// surface (top) and the cache hit rate (bottom, 0-100 %), one line per
// sequence. The first isovalue of each sequence (left out of the summary) is
// drawn hollow.

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

interface Panel {
  top: number;
  height: number;
  max: number;
  ticks: number[];
  label: (v: number) => string;
  value: (r: BenchRecord) => number;
  title: string;
}

export function drawBenchChart(canvas: HTMLCanvasElement, records: BenchRecord[], modes: BenchMode[], count: number): void {
  const dpr = window.devicePixelRatio || 1;
  const cssW = canvas.clientWidth || 300;
  const cssH = canvas.clientHeight || 200;
  canvas.width = Math.round(cssW * dpr);
  canvas.height = Math.round(cssH * dpr);
  const g = canvas.getContext('2d');
  if (!g) return;
  g.setTransform(dpr, 0, 0, dpr, 0, 0);
  g.clearRect(0, 0, cssW, cssH);
  const left = 38,
    right = 6,
    bottom = 16;
  const w = cssW - left - right;
  const x = (i: number) => left + (count > 1 ? (i / (count - 1)) * w : w / 2);
  const maxMs = niceMax(Math.max(0, ...records.map((r) => r.gpuMs)));
  const usable = cssH - bottom - 14 - 14;
  const panels: Panel[] = [
    {
      top: 14,
      height: usable * 0.62,
      max: maxMs,
      ticks: [0, 0.5, 1],
      label: (v) => `${Number((v * maxMs).toPrecision(3))}`,
      value: (r) => r.gpuMs,
      title: 'GPU ms per surface',
    },
    {
      top: 14 + usable * 0.62 + 14,
      height: usable * 0.38,
      max: 1,
      ticks: [0, 0.5, 1],
      label: (v) => `${Math.round(v * 100)}%`,
      value: (r) => r.hitRate,
      title: 'cache hit rate',
    },
  ];
  g.font = '10px system-ui, sans-serif';
  g.lineWidth = 1;
  for (const p of panels) {
    const y = (v: number) => p.top + p.height - (Math.min(v, p.max) / p.max) * p.height;
    g.fillStyle = '#8d95a1';
    g.textAlign = 'right';
    g.fillText(p.title, left + w, p.top - 4);
    for (const t of p.ticks) {
      const yy = Math.round(p.top + p.height - t * p.height) + 0.5;
      g.strokeStyle = '#30343c';
      g.beginPath();
      g.moveTo(left, yy);
      g.lineTo(left + w, yy);
      g.stroke();
      g.textAlign = 'right';
      g.fillText(p.label(t), left - 4, yy + 3);
    }
    for (const mode of modes) {
      const rs = records.filter((r) => r.mode === mode);
      if (rs.length === 0) continue;
      g.strokeStyle = MODE_COLORS[mode];
      g.lineWidth = 1.3;
      g.beginPath();
      rs.forEach((r, i) => (i === 0 ? g.moveTo(x(r.index), y(p.value(r))) : g.lineTo(x(r.index), y(p.value(r)))));
      g.stroke();
      const first = rs.find((r) => r.discarded);
      if (first) {
        g.beginPath();
        g.arc(x(first.index), y(p.value(first)), 2.5, 0, Math.PI * 2);
        g.fillStyle = '#1d2026';
        g.fill();
        g.stroke();
      }
    }
  }
  g.fillStyle = '#8d95a1';
  g.textAlign = 'left';
  g.fillText('1', left, cssH - 3);
  g.textAlign = 'right';
  g.fillText(String(count), left + w, cssH - 3);
  g.textAlign = 'center';
  g.fillText('isovalue # (in sequence order)', left + w / 2, cssH - 3);
}
