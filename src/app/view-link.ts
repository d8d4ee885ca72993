// Keeps the URL hash in step with the view (isovalue and camera), so a copied
// link reopens the same picture: #iso=…&cam=…, next to ?url=… for the volume.
// Writes are throttled (scrubbing and orbiting change them every frame).

import type { ArcballCamera } from '../render/camera.ts';
import { decodeViewState, encodeViewState, writeViewState, type ViewState } from './url-state.ts';

export class ViewLink {
  private timer: ReturnType<typeof setTimeout> | undefined;
  private iso: number | undefined;
  private surfaces: Pick<ViewState, 'surfaces' | 'selected'> = {};
  private clip: ViewState['clip'];
  private draw: ViewState['draw'];
  private spacing: [number, number, number] | undefined;
  private level: number | undefined;
  private storeChoice: Pick<ViewState, 'storeRate' | 'time' | 'channel'> = {};
  private cut: Pick<ViewState, 'cut' | 'tolerancePx' | 'tint'> = {};

  constructor(
    private readonly camera: ArcballCamera,
    /** The canvas in device pixels (written with a store refined by the view: px=W,H). */
    private readonly viewport: () => { width: number; height: number } = () => ({ width: 0, height: 0 }),
  ) {}

  /** A store's refinement: by the view (with its tolerance and tint) or level by level; empty: not a store. */
  setCut(cut: Pick<ViewState, 'cut' | 'tolerancePx' | 'tint'>): void {
    this.cut = { ...cut };
    this.schedule();
  }

  /** What the page was opened with. */
  static initial(): ViewState {
    return decodeViewState(location.hash);
  }

  setIso(iso: number | undefined): void {
    this.iso = iso;
    this.schedule();
  }

  /** Several surfaces (one: the link keeps only iso=). */
  setSurfaces(surfaces: ViewState['surfaces'], selected: number): void {
    this.surfaces = { surfaces, selected };
    this.schedule();
  }

  /** How the surface is drawn (mesh: not written). */
  setDraw(draw: ViewState['draw']): void {
    this.draw = draw;
    this.schedule();
  }

  /** The clip box and plane (undefined: none). */
  setClip(clip: ViewState['clip']): void {
    this.clip = clip;
    this.schedule();
  }

  /** A voxel size the user set (undefined: the file's own, not written). */
  setSpacing(spacing: [number, number, number] | undefined): void {
    this.spacing = spacing;
    this.schedule();
  }

  /** The store level shown (undefined: not a store). */
  setLevel(level: number | undefined): void {
    this.level = level;
    this.schedule();
  }

  /** A store of lossless chunks: its bricks' rate, time point and channel (empty: not such a store). */
  setStoreChoice(choice: Pick<ViewState, 'storeRate' | 'time' | 'channel'>): void {
    this.storeChoice = { ...choice };
    this.schedule();
  }

  schedule(): void {
    if (this.timer !== undefined) return;
    this.timer = setTimeout(() => {
      this.timer = undefined;
      this.flush();
    }, 250);
  }

  flush(): void {
    writeViewState(this.state());
  }

  state(): ViewState {
    const vp = this.viewport();
    return {
      iso: this.iso,
      ...this.surfaces,
      clip: this.clip,
      draw: this.draw,
      camera: this.camera.getState(),
      spacing: this.spacing,
      level: this.level,
      ...this.storeChoice,
      ...this.cut,
      ...(this.cut.cut && vp.width > 0 ? { viewport: { width: vp.width, height: vp.height } } : {}),
    };
  }

  /** The full link to this view. */
  href(): string {
    const hash = encodeViewState(this.state());
    return `${location.origin}${location.pathname}${location.search}${hash ? `#${hash}` : ''}`;
  }
}
