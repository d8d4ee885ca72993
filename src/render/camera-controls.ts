// Mouse, touch and keyboard habits of 3D viewers for an ArcballCamera:
// left-drag rotates, right-drag / shift-drag / middle-drag pans, wheel (or
// pinch) zooms, double-click or R resets, F fits. Calls `onChange` after
// every camera change so the owner can redraw and update the URL.

import type { ArcballCamera } from './camera.ts';

export interface CameraControlsOptions {
  /** Called after any change of the camera. */
  onChange: () => void;
  /** Fit to the data (F key); defaults to reset. */
  onFit?: () => void;
}

export class CameraControls {
  private drag: { mode: 'rotate' | 'pan'; x: number; y: number; id: number } | undefined;
  private readonly disposers: (() => void)[] = [];

  constructor(
    private readonly element: HTMLElement,
    private readonly camera: ArcballCamera,
    private readonly options: CameraControlsOptions,
  ) {
    const on = <K extends keyof HTMLElementEventMap>(type: K, fn: (e: HTMLElementEventMap[K]) => void, opts?: AddEventListenerOptions) => {
      element.addEventListener(type, fn as EventListener, opts);
      this.disposers.push(() => element.removeEventListener(type, fn as EventListener, opts));
    };
    on('contextmenu', (e) => e.preventDefault());
    on('pointerdown', (e) => this.pointerDown(e));
    on('pointermove', (e) => this.pointerMove(e));
    on('pointerup', (e) => this.pointerUp(e));
    on('pointercancel', (e) => this.pointerUp(e));
    on('wheel', (e) => this.wheel(e), { passive: false });
    on('dblclick', () => this.reset());
    on('keydown', (e) => this.key(e));
    if (element.tabIndex < 0) element.tabIndex = 0;
  }

  dispose(): void {
    for (const d of this.disposers) d();
    this.disposers.length = 0;
  }

  reset(): void {
    this.camera.reset();
    this.options.onChange();
  }

  private ndc(e: PointerEvent): [number, number] {
    const r = this.element.getBoundingClientRect();
    return [((e.clientX - r.left) / r.width) * 2 - 1, 1 - ((e.clientY - r.top) / r.height) * 2];
  }

  private pointerDown(e: PointerEvent): void {
    if (this.drag) return;
    const pan = e.button === 2 || e.button === 1 || e.shiftKey;
    const [x, y] = this.ndc(e);
    this.drag = { mode: pan ? 'pan' : 'rotate', x, y, id: e.pointerId };
    this.element.setPointerCapture(e.pointerId);
    this.element.focus({ preventScroll: true });
    e.preventDefault();
  }

  private pointerMove(e: PointerEvent): void {
    const d = this.drag;
    if (!d || d.id !== e.pointerId) return;
    const [x, y] = this.ndc(e);
    if (d.mode === 'rotate') this.camera.rotateArcball(d.x, d.y, x, y);
    else this.camera.pan(x - d.x, y - d.y);
    d.x = x;
    d.y = y;
    this.options.onChange();
  }

  private pointerUp(e: PointerEvent): void {
    if (this.drag?.id !== e.pointerId) return;
    this.drag = undefined;
    if (this.element.hasPointerCapture(e.pointerId)) this.element.releasePointerCapture(e.pointerId);
  }

  private wheel(e: WheelEvent): void {
    e.preventDefault();
    // Trackpads send small pixel deltas, mice larger line deltas.
    const delta = e.deltaMode === 1 ? e.deltaY * 16 : e.deltaY;
    this.camera.zoom(Math.exp(delta * 0.0015));
    this.options.onChange();
  }

  private key(e: KeyboardEvent): void {
    if (e.target !== this.element || e.ctrlKey || e.metaKey || e.altKey) return;
    const k = e.key.toLowerCase();
    if (k === 'r') this.reset();
    else if (k === 'f') {
      if (this.options.onFit) this.options.onFit();
      else this.reset();
      this.options.onChange();
    } else if (k === '+' || k === '=') {
      this.camera.zoom(0.9);
      this.options.onChange();
    } else if (k === '-') {
      this.camera.zoom(1 / 0.9);
      this.options.onChange();
    } else return;
    e.preventDefault();
  }
}
