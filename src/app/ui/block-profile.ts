// "How many blocks does the surface touch at each isovalue?" computed from the
// per-block [min, max] ranges (read once at load): a profile drawn under the
// isovalue slider so users see where surfaces are and what they cost.

import { fitCanvas2d } from './canvas-2d.ts';

export interface BlockProfile {
  lo: number;
  hi: number;
  /** Blocks whose range contains the bin's centre value. */
  counts: Uint32Array;
}

/** ranges: [min0, max0, min1, max1, ...] per block. */
export function computeBlockProfile(ranges: Float32Array, lo: number, hi: number, bins = 256): BlockProfile {
  const delta = new Int32Array(bins + 1);
  const width = (hi - lo) / bins || 1;
  for (let i = 0; i < ranges.length; i += 2) {
    const a = ranges[i];
    const b = ranges[i + 1];
    if (!(b >= a)) continue; // NaN or empty
    // Bins whose centre lies in [a, b].
    const first = Math.max(0, Math.ceil((a - lo) / width - 0.5));
    const last = Math.min(bins - 1, Math.floor((b - lo) / width - 0.5));
    if (last < first) continue;
    delta[first]++;
    delta[last + 1]--;
  }
  const counts = new Uint32Array(bins);
  let run = 0;
  for (let i = 0; i < bins; i++) counts[i] = run += delta[i];
  return { lo, hi, counts };
}

/** Draws the profile (log scale) and a marker at `iso`. */
export function drawBlockProfile(canvas: HTMLCanvasElement, profile: BlockProfile, iso: number | undefined): void {
  const fitted = fitCanvas2d(canvas);
  if (!fitted) return;
  const { g, w, h, dpr } = fitted;
  const n = profile.counts.length;
  let max = 1;
  for (const c of profile.counts) max = Math.max(max, c);
  const scale = Math.log1p(max);
  g.fillStyle = 'rgba(108, 180, 255, 0.55)';
  for (let i = 0; i < n; i++) {
    const bh = (Math.log1p(profile.counts[i]) / scale) * h;
    g.fillRect((i / n) * w, h - bh, Math.ceil(w / n), bh);
  }
  if (iso !== undefined && profile.hi > profile.lo) {
    const x = ((iso - profile.lo) / (profile.hi - profile.lo)) * w;
    g.fillStyle = '#ffd166';
    g.fillRect(Math.round(x) - Math.round(dpr), 0, Math.max(2, Math.round(2 * dpr)), h);
  }
}
