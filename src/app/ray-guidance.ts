// The page's rays over a store refined where they found the surface (issue
// 46), as `render` does headless (src/cli/guide-rays.ts): once the rays draw
// a plan's final step and the view has rested a moment, they are drawn once
// more offscreen, smaller, in the canvas' shape, and their depth alone read
// back (READ_BYTES at most: within the budget's reserve for short-lived
// buffers, RESERVE_BYTES); each
// covered pixel's first hit (src/store/view/seen.ts) goes to the store's
// surface (StoreIsosurface.guideRays), which has the stream refine there: a
// cut for rays, finer chunks only where the rays hit. The next final step
// is read the same way, until its rays hit nothing new (at most
// MAX_GUIDED_PASSES per view; a camera move or a new isovalue starts over).
import { mat4 } from 'gl-matrix';
import { renderOffscreen } from '../render/offscreen.ts';
import type { RayLayer } from '../render/ray-layer.ts';
import type { Viewer } from '../render/viewer.ts';
import { hitsFromDepth } from '../store/view/seen.ts';
import type { PageIsosurface, PageRayLevels } from './engine.ts';

/** How long a final step is on screen, still, before its rays are read. */
const GUIDE_DELAY_MS = 300;
/** Bytes of depth read back at most (rows padded to 256 bytes). */
const READ_BYTES = 512 * 1024;

export class RayGuidance {
  /** The step last read (or waiting to be). */
  #step: unknown;
  #timer: ReturnType<typeof setTimeout> | undefined;
  #busy = false;
  /** Times the rays' depth was read and a refinement asked for (the page's state). */
  asked = 0;

  constructor(
    private readonly viewer: Viewer,
    private readonly rays: () => RayLayer,
  ) {}

  /** The rays draw `iso`'s step (each frame): a final step not read yet is read once the view rests. */
  drew(iso: PageIsosurface, store: PageRayLevels, voxelSize: readonly number[], origin: readonly number[]): void {
    if (!store.final || !iso.guideRays || store.step === this.#step) return;
    this.#step = store.step;
    clearTimeout(this.#timer);
    this.#timer = setTimeout(() => {
      this.#timer = undefined;
      void this.#read(iso, store.step, [...voxelSize], [...origin]);
    }, GUIDE_DELAY_MS);
  }

  /** Whether a step's rays are waiting to be read or being read (the page's state: raysGuiding). */
  get pending(): boolean {
    return this.#timer !== undefined || this.#busy;
  }

  /** Nothing to read (rays off, another volume). */
  cancel(): void {
    clearTimeout(this.#timer);
    this.#timer = undefined;
    this.#step = undefined;
  }

  async #read(iso: PageIsosurface, step: unknown, voxelSize: number[], origin: number[]): Promise<void> {
    if (this.#busy || iso.rayLevels?.()?.step !== step) return;
    const { viewer } = this;
    const rays = this.rays();
    if (!rays.visible) return;
    this.#busy = true;
    try {
      const camera = viewer.camera;
      const { width: cw, height: ch } = viewer.canvas;
      let scale = 1;
      const size = () => [Math.max(16, Math.round(cw * scale)), Math.max(16, Math.round(ch * scale))];
      const bytes = ([w, h]: number[]) => 256 * Math.ceil((4 * w) / 256) * h;
      while (bytes(size()) > READ_BYTES && scale > 1e-3) scale *= 0.9;
      const [width, height] = size();
      const image = await renderOffscreen(viewer.device, viewer.frameBindGroupLayout, camera, width, height, rays, {
        format: viewer.format,
        colour: false,
      });
      // the step may have gone while the image was read
      if (iso.rayLevels?.()?.step !== step) return;
      const inverse = mat4.invert(mat4.create(), camera.viewProjection(mat4.create()));
      if (!inverse) return;
      if (iso.guideRays!(hitsFromDepth(image.depth, [width, height], inverse, camera.eyePosition(), voxelSize, origin))) this.asked++;
    } catch {
      // an optimisation only: a lost device or a destroyed surface is reported where it happens
    } finally {
      this.#busy = false;
      viewer.requestFrame();
    }
  }
}
