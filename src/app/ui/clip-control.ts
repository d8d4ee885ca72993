// The clip: a box (a lower and an upper slider per axis, in voxels of the
// volume's level 0) and one free plane (its normal along x, y, z, the view
// direction or any direction, typed as nx,ny,nz or set by its handles in the
// view; its offset on a slider, flipped with a button; `,` and `.` step it
// along its normal, Shift x10). Every change calls onChange with the clip
// (src/core/clip.ts) or undefined when both are off. A clip from the link is
// checked against the volume: one that holds no cell of it is refused with a
// message and the clip stays as it was.
import { type Clip, type ClipBox, type ClipPlane, parseClipBox } from '../../core/clip.ts';
import type { Messages } from '../messages.ts';

export interface ClipElements {
  boxOn: HTMLInputElement;
  /** x0, x1, y0, y1, z0, z1 */
  box: HTMLInputElement[];
  boxLabels: HTMLElement[];
  planeOn: HTMLInputElement;
  planeAxis: HTMLSelectElement;
  /** The normal's components, shown and typed (nx, ny, nz; made unit length). */
  planeNormal: HTMLInputElement;
  planeOffset: HTMLInputElement;
  planeLabel: HTMLElement;
  planeFlip: HTMLButtonElement;
}

export class ClipControl {
  #dims: readonly number[] = [2, 2, 2];
  #normal: [number, number, number] = [1, 0, 0];

  constructor(
    private readonly els: ClipElements,
    private readonly onChange: (clip: Clip | undefined) => void,
    /** The camera's view direction in voxel coordinates (away from the eye), for a plane facing the view. */
    private readonly viewDirection: () => [number, number, number],
    private readonly messages: Messages,
  ) {
    els.boxOn.addEventListener('change', () => this.#changed());
    els.box.forEach((input, i) =>
      input.addEventListener('input', () => {
        // the lower slider stays below the upper one
        const a = i >> 1;
        const lo = els.box[2 * a],
          hi = els.box[2 * a + 1];
        if (Number(lo.value) >= Number(hi.value)) {
          if (i % 2 === 0) lo.value = String(Number(hi.value) - 1);
          else hi.value = String(Number(lo.value) + 1);
        }
        els.boxOn.checked = true;
        this.#changed();
      }),
    );
    els.planeOn.addEventListener('change', () => this.#changed());
    els.planeAxis.addEventListener('change', () => {
      this.#setNormal(this.#axisNormal(els.planeAxis.value));
      els.planeOn.checked = true;
      this.#changed();
    });
    els.planeNormal.addEventListener('change', () => {
      const v = els.planeNormal.value
        .split(/[\s,]+/)
        .filter((t) => t !== '')
        .map(Number);
      const len = Math.hypot(v[0], v[1], v[2]);
      if (v.length !== 3 || !(len > 0) || !Number.isFinite(len)) {
        this.messages.show(`Plane normal "${els.planeNormal.value}": three numbers nx, ny, nz, not all zero; the plane stays as it was.`);
        this.#showNormal();
        return;
      }
      this.#setNormal([v[0] / len, v[1] / len, v[2] / len]);
      els.planeAxis.value = this.#axisName(this.#normal);
      els.planeOn.checked = true;
      this.#changed();
    });
    els.planeOffset.addEventListener('input', () => {
      els.planeOn.checked = true;
      this.#changed();
    });
    els.planeFlip.addEventListener('click', () => {
      const d = Number(els.planeOffset.value);
      this.#setNormal([-this.#normal[0], -this.#normal[1], -this.#normal[2]]);
      els.planeOffset.value = String(-d);
      els.planeOn.checked = true;
      this.#changed();
    });
  }

  /** The volume's level-0 grid points per axis (setVolume's; the same array until the next volume). */
  get dims(): readonly number[] {
    return this.#dims;
  }

  /** The clip now (undefined: nothing clipped). */
  get clip(): Clip | undefined {
    const box = this.els.boxOn.checked ? this.#box() : undefined;
    const plane = this.els.planeOn.checked ? this.#plane() : undefined;
    return box || plane ? { ...(box ? { box } : {}), ...(plane ? { plane } : {}) } : undefined;
  }

  /** A new volume: the sliders span its level-0 grid; the clip is off unless `clip` (a link's) is given and meets it. */
  setVolume(dims: readonly number[], clip?: Clip): void {
    this.#dims = dims;
    const { box } = this.els;
    for (let a = 0; a < 3; a++) {
      for (const input of [box[2 * a], box[2 * a + 1]]) {
        input.min = '0';
        input.max = String(dims[a] - 1);
        input.step = '1';
      }
      box[2 * a].value = '0';
      box[2 * a + 1].value = String(dims[a] - 1);
    }
    this.els.boxOn.checked = false;
    this.els.planeOn.checked = false;
    this.#setNormal([1, 0, 0]);
    this.els.planeAxis.value = 'x';
    this.els.planeOffset.value = String(Math.floor((dims[0] - 1) / 2));
    if (clip) this.apply(clip);
    else this.#changed();
  }

  /** A clip given whole (the link): refused with a message when its box holds no cell of the volume. */
  apply(clip: Clip): boolean {
    if (clip.box) {
      const ok = parseClipBox(clip.box.join(','), this.#dims);
      if (typeof ok === 'string') {
        this.messages.show(`Clip box ${clip.box.join(',')}: ${ok}; the clip stays as it was.`);
        return false;
      }
      clip.box.forEach((v, i) => {
        // box order x0,y0,z0,x1,y1,z1 -> sliders x0,x1,y0,y1,z0,z1
        this.els.box[2 * (i % 3) + (i >= 3 ? 1 : 0)].value = String(v);
      });
      this.els.boxOn.checked = true;
    }
    if (clip.plane) {
      const n = clip.plane.normal;
      const len = Math.hypot(n[0], n[1], n[2]);
      this.#setNormal([n[0] / len, n[1] / len, n[2] / len]);
      this.els.planeAxis.value = this.#axisName(this.#normal);
      this.els.planeOffset.value = String(clip.plane.d / len);
      this.els.planeOn.checked = true;
    }
    this.#changed();
    return true;
  }

  /** Moves one face of the box (axis 0..2, side 0 lower or 1 upper) to `value`, kept inside the volume and the other face. */
  setBoxFace(axis: number, side: 0 | 1, value: number): void {
    const lo = this.els.box[2 * axis],
      hi = this.els.box[2 * axis + 1];
    if (side === 0) lo.value = String(Math.max(0, Math.min(Number(hi.value) - 1, value)));
    else hi.value = String(Math.min(this.#dims[axis] - 1, Math.max(Number(lo.value) + 1, value)));
    this.els.boxOn.checked = true;
    this.#changed();
  }

  /** A plane from the view's handles: any normal (made unit length), its offset as given (the slider's range follows the normal). */
  setPlane(plane: ClipPlane): void {
    const n = plane.normal;
    const len = Math.hypot(n[0], n[1], n[2]);
    if (!(len > 0)) return;
    this.#setNormal([n[0] / len, n[1] / len, n[2] / len]);
    this.els.planeOffset.value = String(plane.d / len);
    this.els.planeAxis.value = this.#axisName(this.#normal);
    this.els.planeOn.checked = true;
    this.#changed();
  }

  /** Moves the plane along its normal by `steps` voxels (keys , and .). */
  stepPlane(steps: number): void {
    if (!this.els.planeOn.checked) return;
    const o = this.els.planeOffset;
    o.value = String(Math.min(Number(o.max), Math.max(Number(o.min), Number(o.value) + steps)));
    this.#changed();
  }

  #box(): ClipBox {
    const v = this.els.box.map((i) => Number(i.value));
    return [v[0], v[2], v[4], v[1], v[3], v[5]];
  }

  #plane(): ClipPlane {
    return { normal: [...this.#normal], d: Number(this.els.planeOffset.value) };
  }

  #axisNormal(axis: string): [number, number, number] {
    if (axis === 'y') return [0, 1, 0];
    if (axis === 'z') return [0, 0, 1];
    if (axis === 'free') return this.#normal;
    if (axis === 'view') {
      const v = this.viewDirection();
      const len = Math.hypot(v[0], v[1], v[2]) || 1;
      return [v[0] / len, v[1] / len, v[2] / len];
    }
    return [1, 0, 0];
  }

  #axisName(n: readonly number[]): string {
    const named = ['x', 'y', 'z'].find((_, a) => n[a] === 1);
    return named ?? 'free';
  }

  /** A new normal: the offset slider spans n . x over the volume's corners, the offset kept inside. */
  #setNormal(n: [number, number, number]): void {
    this.#normal = n;
    let lo = 0,
      hi = 0;
    for (let a = 0; a < 3; a++) {
      const ext = n[a] * (this.#dims[a] - 1);
      lo += Math.min(0, ext);
      hi += Math.max(0, ext);
    }
    const o = this.els.planeOffset;
    o.min = String(Math.floor(lo));
    o.max = String(Math.ceil(hi));
    o.step = 'any';
    o.value = String(Math.min(hi, Math.max(lo, Number(o.value))));
    this.#showNormal();
  }

  #showNormal(): void {
    this.els.planeNormal.value = this.#normal.map((v) => Number(v.toFixed(4))).join(', ');
  }

  #changed(): void {
    const box = this.#box();
    const names = ['x', 'y', 'z'];
    this.els.boxLabels.forEach((l, a) => {
      l.textContent = `${names[a]} ${box[a]} … ${box[a + 3]}`;
    });
    const d = Number(this.els.planeOffset.value);
    this.els.planeLabel.textContent = `${this.#normal.map((v) => Number(v.toFixed(3))).join(', ')} · x ≥ ${Number(d.toFixed(2))}`;
    this.onChange(this.clip);
  }
}
