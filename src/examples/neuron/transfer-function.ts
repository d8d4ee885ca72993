// Transfer functions for the volume renderer: a colour map and an opacity
// ramp over the window [lo, hi] of normalised data values, baked into a
// 256-entry RGBA texture, and drawn as a small preview for the panel.

import { fitCanvas2d } from '../../app/ui/canvas-2d.ts';

export type ColormapName = 'fluorescence' | 'grayscale' | 'hot' | 'viridis' | 'magma' | 'cool';

type Stops = [number, [number, number, number]][];

// Control points (position, sRGB 0..1); linear interpolation in between.
const COLORMAPS: Record<ColormapName, Stops> = {
  // Black to green to white, the usual look of fluorescence microscopy.
  fluorescence: [
    [0, [0, 0.05, 0]],
    [0.45, [0.1, 0.75, 0.2]],
    [0.8, [0.6, 1, 0.55]],
    [1, [1, 1, 1]],
  ],
  grayscale: [
    [0, [0, 0, 0]],
    [1, [1, 1, 1]],
  ],
  hot: [
    [0, [0.05, 0, 0]],
    [0.35, [0.85, 0.12, 0]],
    [0.7, [1, 0.75, 0.1]],
    [1, [1, 1, 0.95]],
  ],
  viridis: [
    [0, [0.267, 0.005, 0.329]],
    [0.25, [0.229, 0.322, 0.546]],
    [0.5, [0.128, 0.567, 0.551]],
    [0.75, [0.369, 0.789, 0.383]],
    [1, [0.993, 0.906, 0.144]],
  ],
  magma: [
    [0, [0.001, 0.0, 0.014]],
    [0.25, [0.317, 0.071, 0.485]],
    [0.5, [0.716, 0.215, 0.475]],
    [0.75, [0.987, 0.536, 0.382]],
    [1, [0.987, 0.991, 0.75]],
  ],
  cool: [
    [0, [0, 0.05, 0.15]],
    [0.5, [0.1, 0.6, 0.95]],
    [1, [0.9, 0.98, 1]],
  ],
};

export const COLORMAP_NAMES = Object.keys(COLORMAPS) as ColormapName[];

export function colormap(name: ColormapName, t: number): [number, number, number] {
  const stops = COLORMAPS[name];
  const x = Math.min(1, Math.max(0, t));
  for (let i = 1; i < stops.length; i++) {
    const [p1, c1] = stops[i];
    if (x <= p1) {
      const [p0, c0] = stops[i - 1];
      const f = (x - p0) / Math.max(p1 - p0, 1e-9);
      return [c0[0] + (c1[0] - c0[0]) * f, c0[1] + (c1[1] - c0[1]) * f, c0[2] + (c1[2] - c0[2]) * f];
    }
  }
  return stops[stops.length - 1][1];
}

export interface TransferFunction {
  colormap: ColormapName;
  /** Opacity ramp exponent: > 1 keeps faint signal transparent. */
  gamma: number;
}

/** 256 RGBA8 entries over s in [0, 1] (s = position inside the window). */
export function bakeTransferFunction(tf: TransferFunction): Uint8Array<ArrayBuffer> {
  const out = new Uint8Array(256 * 4);
  for (let i = 0; i < 256; i++) {
    const s = i / 255;
    const [r, g, b] = colormap(tf.colormap, s);
    const a = Math.pow(s, tf.gamma);
    out.set(
      [r * 255, g * 255, b * 255, a * 255].map((v) => Math.round(Math.min(255, Math.max(0, v)))),
      i * 4,
    );
  }
  return out;
}

/**
 * Draws the transfer function over the data's histogram: the colour ramp as
 * the fill, the opacity curve as a line, and the window as handles.
 */
export function drawTransferFunction(
  canvas: HTMLCanvasElement,
  tf: TransferFunction,
  windowLo: number,
  windowHi: number,
  histogram: Float64Array | undefined,
): void {
  const fitted = fitCanvas2d(canvas, 2);
  if (!fitted) return;
  const { g, w, h, dpr } = fitted;
  // Histogram (log counts) as a faint backdrop.
  if (histogram && histogram.length > 0) {
    let max = 0;
    for (const v of histogram) max = Math.max(max, Math.log1p(v));
    g.fillStyle = 'rgba(141, 149, 161, 0.35)';
    const bw = w / histogram.length;
    for (let i = 0; i < histogram.length; i++) {
      const bh = max > 0 ? (Math.log1p(histogram[i]) / max) * (h - 4) : 0;
      g.fillRect(i * bw, h - bh, Math.ceil(bw), bh);
    }
  }
  // Colour and opacity over the whole data range.
  g.beginPath();
  g.moveTo(0, h);
  for (let x = 0; x <= w; x++) {
    const v = x / w;
    const s = (v - windowLo) / Math.max(windowHi - windowLo, 1e-6);
    const a = s <= 0 ? 0 : Math.pow(Math.min(1, s), tf.gamma);
    g.lineTo(x, h - a * (h - 2) - 1);
  }
  g.lineTo(w, h);
  g.closePath();
  const grad = g.createLinearGradient(windowLo * w, 0, Math.max(windowHi * w, windowLo * w + 1), 0);
  for (let i = 0; i <= 8; i++) {
    const [r, gg, b] = colormap(tf.colormap, i / 8);
    grad.addColorStop(i / 8, `rgba(${Math.round(r * 255)},${Math.round(gg * 255)},${Math.round(b * 255)},0.85)`);
  }
  g.fillStyle = grad;
  g.fill();
  g.strokeStyle = 'rgba(221, 225, 231, 0.9)';
  g.lineWidth = dpr;
  g.stroke();
  // Window handles.
  g.fillStyle = '#6cb4ff';
  for (const v of [windowLo, windowHi]) g.fillRect(Math.round(v * w) - dpr, 0, 2 * dpr, h);
}
