/**
 * Sizes a 2D canvas's backing store to its CSS box at the device pixel ratio
 * (capped at maxDpr: charts gain nothing from more pixels), and returns its
 * cleared context with the size in device pixels, or undefined when the
 * browser gives no 2D context.
 */
export function fitCanvas2d(
  canvas: HTMLCanvasElement,
  maxDpr = Infinity,
): { g: CanvasRenderingContext2D; w: number; h: number; dpr: number } | undefined {
  const dpr = Math.min(maxDpr, window.devicePixelRatio || 1);
  const w = Math.max(1, Math.round(canvas.clientWidth * dpr));
  const h = Math.max(1, Math.round(canvas.clientHeight * dpr));
  if (canvas.width !== w || canvas.height !== h) {
    canvas.width = w;
    canvas.height = h;
  }
  const g = canvas.getContext('2d');
  if (!g) return undefined;
  g.setTransform(1, 0, 0, 1, 0, 0);
  g.clearRect(0, 0, w, h);
  return { g, w, h, dpr };
}
