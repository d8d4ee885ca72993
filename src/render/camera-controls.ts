// Mouse, touch and keyboard habits of 3D viewers for an ArcballCamera:
// left-drag rotates, right-drag / shift-drag / middle-drag pans, wheel (or
// trackpad pinch) zooms, double-click or R resets, F fits; on touch screens
// one finger rotates and two pinch to zoom and move together to pan; a left
// press the owner grabs (a handle under it, or Ctrl/Cmd on a face) drags
// that instead of the camera. Calls
// `onChange` after every camera change so the owner can redraw and update
// the URL.

import type { ArcballCamera } from './camera.ts';

export interface CameraControlsOptions {
  /** Called after any change of the camera. */
  onChange: () => void;
  /** Fit to the data (F key); defaults to reset. */
  onFit?: () => void;
  /** A left click that did not drag (moved under 4 px): where, as fractions of the element from its top left. */
  onClick?: (u: number, v: number) => void;
  /**
   * A left press (mouse or pen; not Shift, which pans): the owner's drag, not
   * the camera's, when `grab` takes it (true: something under the pointer
   * was grabbed, e.g. a handle, or a clip box face when `modifier`, Ctrl or
   * Cmd, is held); then `grabMove` follows the pointer and `grabEnd` ends it.
   */
  grab?: (u: number, v: number, modifier: boolean) => boolean;
  grabMove?: (u: number, v: number) => void;
  grabEnd?: () => void;
  /** The mouse moves with no button down: the cursor to show there ('' the default; undefined leaves it). */
  hover?: (u: number, v: number) => string | undefined;
}

export class CameraControls {
  private drag: { mode: 'rotate' | 'pan' | 'grab'; x: number; y: number; id: number } | undefined;
  /** Fingers on the element (client pixels), by pointer id. */
  private readonly touches = new Map<number, [number, number]>();
  /** Two fingers down: their distance (pixels) and midpoint (NDC) at the last move. */
  private pinch: { distance: number; mid: [number, number] } | undefined;
  private readonly disposers: (() => void)[] = [];
  /** Where a left button went down (client pixels): a release there is a click. */
  private press: { id: number; x: number; y: number; moved: boolean } | undefined;

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

  private ndc(clientX: number, clientY: number): [number, number] {
    const r = this.element.getBoundingClientRect();
    return [((clientX - r.left) / r.width) * 2 - 1, 1 - ((clientY - r.top) / r.height) * 2];
  }

  private pointerDown(e: PointerEvent): void {
    if (e.pointerType === 'touch') {
      this.touches.set(e.pointerId, [e.clientX, e.clientY]);
      this.capture(e);
      if (this.touches.size === 2) {
        // A second finger turns the one-finger rotation into pinch and pan.
        this.drag = undefined;
        this.pinch = this.pinchState();
      } else if (this.touches.size === 1) {
        this.startDrag('rotate', e.pointerId, e.clientX, e.clientY);
      }
      return;
    }
    if (this.drag) return;
    if (e.button === 0 && !e.shiftKey && this.options.grab) {
      const [u, v] = this.fractions(e);
      if (this.options.grab(u, v, e.ctrlKey || e.metaKey)) {
        this.drag = { mode: 'grab', x: u, y: v, id: e.pointerId };
        this.press = undefined;
        this.element.style.cursor = 'grabbing';
        this.capture(e);
        return;
      }
    }
    const pan = e.button === 2 || e.button === 1 || e.shiftKey;
    this.press = !pan && e.button === 0 ? { id: e.pointerId, x: e.clientX, y: e.clientY, moved: false } : undefined;
    this.startDrag(pan ? 'pan' : 'rotate', e.pointerId, e.clientX, e.clientY);
    this.capture(e);
  }

  /** Where the pointer is, as fractions of the element from its top left. */
  private fractions(e: PointerEvent): [number, number] {
    const r = this.element.getBoundingClientRect();
    return [(e.clientX - r.left) / r.width, (e.clientY - r.top) / r.height];
  }

  private startDrag(mode: 'rotate' | 'pan', id: number, clientX: number, clientY: number): void {
    const [x, y] = this.ndc(clientX, clientY);
    this.drag = { mode, x, y, id };
  }

  private capture(e: PointerEvent): void {
    this.element.setPointerCapture(e.pointerId);
    this.element.focus({ preventScroll: true });
    e.preventDefault();
  }

  private pinchState(): { distance: number; mid: [number, number] } {
    const [a, b] = [...this.touches.values()];
    return {
      distance: Math.max(1, Math.hypot(a[0] - b[0], a[1] - b[1])),
      mid: this.ndc((a[0] + b[0]) / 2, (a[1] + b[1]) / 2),
    };
  }

  private pointerMove(e: PointerEvent): void {
    if (this.touches.has(e.pointerId)) {
      this.touches.set(e.pointerId, [e.clientX, e.clientY]);
      if (this.pinch && this.touches.size >= 2) {
        const now = this.pinchState();
        this.camera.zoom(this.pinch.distance / now.distance);
        this.camera.pan(now.mid[0] - this.pinch.mid[0], now.mid[1] - this.pinch.mid[1]);
        this.pinch = now;
        this.options.onChange();
        return;
      }
    }
    const d = this.drag;
    if (!d && e.pointerType === 'mouse' && this.options.hover) {
      const cursor = this.options.hover(...this.fractions(e));
      if (cursor !== undefined) this.element.style.cursor = cursor;
    }
    if (!d || d.id !== e.pointerId) return;
    if (d.mode === 'grab') {
      this.options.grabMove?.(...this.fractions(e));
      return;
    }
    const p = this.press;
    if (p && p.id === e.pointerId && Math.hypot(e.clientX - p.x, e.clientY - p.y) >= 4) p.moved = true;
    // a click's own few pixels of jitter do not turn the camera
    if (p && p.id === e.pointerId && !p.moved) return;
    const [x, y] = this.ndc(e.clientX, e.clientY);
    if (d.mode === 'rotate') this.camera.rotateArcball(d.x, d.y, x, y);
    else this.camera.pan(x - d.x, y - d.y);
    d.x = x;
    d.y = y;
    this.options.onChange();
  }

  private pointerUp(e: PointerEvent): void {
    if (this.touches.delete(e.pointerId)) {
      // The fingers left carry on from where they are, without a jump: two or more pinch, one rotates.
      this.pinch = this.touches.size >= 2 ? this.pinchState() : undefined;
      this.drag = undefined;
      if (this.touches.size === 1) {
        const [[id, [x, y]]] = this.touches;
        this.startDrag('rotate', id, x, y);
      }
    } else if (this.drag?.id === e.pointerId) {
      if (this.drag.mode === 'grab') {
        this.options.grabEnd?.();
        this.element.style.cursor = this.options.hover?.(...this.fractions(e)) ?? '';
      }
      this.drag = undefined;
      const p = this.press;
      this.press = undefined;
      if (p && p.id === e.pointerId && !p.moved && this.options.onClick) this.options.onClick(...this.fractions(e));
    } else return;
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
