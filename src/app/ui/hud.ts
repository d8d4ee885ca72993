// A one-line readout over the view: isovalue, triangles, last surface time,
// frame rate (or "idle" when nothing is being drawn).

import { formatMs, formatShortCount } from '../format.ts';

export class Hud {
  private text = '';
  private framesSeen = 0;
  /** The frame rate as the panel shows it. */
  fpsLabel = 'idle (drawn on demand)';

  constructor(
    private readonly root: HTMLElement,
    private readonly viewer: { readonly fps: number; readonly framesDrawn: number },
    private readonly onFps?: (text: string) => void,
  ) {
    setInterval(() => this.render(), 500);
  }

  setSurface(iso: string, triangles: number, ms: number): void {
    this.text = `iso ${iso} · ${formatShortCount(triangles)} triangles · ${formatMs(ms)}`;
    this.render();
  }

  clear(): void {
    this.text = '';
    this.render();
  }

  /** Frames per second while drawing, or undefined when idle. */
  fps(): number | undefined {
    return this.viewer.framesDrawn !== this.framesSeen && this.viewer.fps > 0 ? this.viewer.fps : undefined;
  }

  private render(): void {
    const fps = this.fps();
    this.framesSeen = this.viewer.framesDrawn;
    const rate = fps === undefined ? 'idle' : `${fps.toFixed(0)} fps`;
    this.root.textContent = this.text ? `${this.text} · ${rate}` : '';
    this.fpsLabel = fps === undefined ? 'idle (drawn on demand)' : `${fps.toFixed(0)} fps`;
    this.onFps?.(this.fpsLabel);
  }
}
