// The isovalue: a slider over the volume's value range, a number field, the
// blocks-per-isovalue profile under them (click or drag on it to pick a
// value), and keyboard steps. Every change calls onInput at once (the
// pipeline drops stale values itself), so scrubbing is continuous.

import { drawBlockProfile, type BlockProfile } from './block-profile.ts';
import { formatIso } from '../format.ts';

const SLIDER_STEPS = 10000;

export interface IsoControlElements {
  slider: HTMLInputElement;
  number: HTMLInputElement;
  profile: HTMLCanvasElement;
  readout: HTMLElement;
  min: HTMLElement;
  max: HTMLElement;
}

export class IsoControl {
  private lo = 0;
  private hi = 1;
  private iso = 0.5;
  private profile: BlockProfile | undefined;
  private enabled = false;

  constructor(
    private readonly els: IsoControlElements,
    private readonly onInput: (iso: number) => void,
  ) {
    const { slider, number, profile } = els;
    slider.addEventListener('input', () => this.change(this.fromSlider(Number(slider.value)), 'slider'));
    slider.addEventListener('keydown', (e) => {
      const dir = { ArrowRight: 1, ArrowUp: 1, ArrowLeft: -1, ArrowDown: -1, PageUp: 10, PageDown: -10 }[e.key];
      if (dir !== undefined) {
        e.preventDefault();
        this.step(dir * (e.shiftKey ? 10 : 1));
      } else if (e.key === 'Home' || e.key === 'End') {
        e.preventDefault();
        this.change(e.key === 'Home' ? this.lo : this.hi);
      }
    });
    number.addEventListener('input', () => {
      const v = number.valueAsNumber;
      if (Number.isFinite(v) && v >= this.lo && v <= this.hi) this.change(v, 'number');
    });
    number.addEventListener('change', () => {
      const v = number.valueAsNumber;
      this.change(Number.isFinite(v) ? Math.min(this.hi, Math.max(this.lo, v)) : this.iso);
    });
    let dragging = false;
    const pick = (e: PointerEvent) => {
      const r = profile.getBoundingClientRect();
      const t = Math.min(1, Math.max(0, (e.clientX - r.left) / r.width));
      return this.lo + t * (this.hi - this.lo);
    };
    profile.addEventListener('pointerdown', (e) => {
      if (!this.enabled) return;
      dragging = true;
      profile.setPointerCapture(e.pointerId);
      this.change(pick(e));
    });
    profile.addEventListener('pointermove', (e) => {
      if (dragging) this.change(pick(e));
      this.showReadout(pick(e));
    });
    profile.addEventListener('pointerup', () => (dragging = false));
    profile.addEventListener('pointerleave', () => this.showReadout(undefined));
    new ResizeObserver(() => this.redraw()).observe(profile);
  }

  get value(): number {
    return this.iso;
  }

  get range(): [number, number] {
    return [this.lo, this.hi];
  }

  setEnabled(on: boolean): void {
    this.enabled = on;
    this.els.slider.disabled = !on;
    this.els.number.disabled = !on;
    this.els.profile.classList.toggle('disabled', !on);
  }

  /** A new volume: its value range, block profile and starting isovalue. */
  setVolume(range: [number, number], profile: BlockProfile | undefined, iso: number): void {
    this.lo = range[0];
    this.hi = range[1] > range[0] ? range[1] : range[0] + 1;
    this.profile = profile;
    const { number, min, max } = this.els;
    number.min = String(this.lo);
    number.max = String(this.hi);
    number.step = String(Number(((this.hi - this.lo) / 1000).toPrecision(2)));
    min.textContent = formatIso(this.lo, this.range);
    max.textContent = formatIso(this.hi, this.range);
    this.setValue(iso);
  }

  /**
   * Sets the value without calling onInput (e.g. while a benchmark drives the
   * surface). A value outside the range is kept as it is (a link's isovalue
   * over a store's provisional range): the number shows it, the slider sits
   * at the end.
   */
  setValue(iso: number): void {
    this.iso = iso;
    this.sync();
  }

  /** Moves by `steps` of 1/200 of the range. */
  step(steps: number): void {
    if (!this.enabled) return;
    this.change(Math.min(this.hi, Math.max(this.lo, this.iso + (steps * (this.hi - this.lo)) / 200)));
  }

  private fromSlider(s: number): number {
    return this.lo + (s / SLIDER_STEPS) * (this.hi - this.lo);
  }

  private change(iso: number, from?: 'slider' | 'number'): void {
    if (!this.enabled) return;
    this.iso = iso;
    this.sync(from);
    this.onInput(iso);
  }

  private sync(from?: 'slider' | 'number'): void {
    const { slider, number } = this.els;
    if (from !== 'slider') slider.value = String(Math.round(((this.iso - this.lo) / (this.hi - this.lo)) * SLIDER_STEPS));
    if (from !== 'number') number.value = formatIso(this.iso, this.range);
    slider.setAttribute('aria-valuetext', formatIso(this.iso, this.range));
    this.redraw();
  }

  private redraw(): void {
    if (this.profile) drawBlockProfile(this.els.profile, this.profile, this.iso);
  }

  private showReadout(iso: number | undefined): void {
    const out = this.els.readout;
    if (iso === undefined || !this.profile || !this.enabled) {
      out.textContent = '';
      return;
    }
    const p = this.profile;
    const bin = Math.min(p.counts.length - 1, Math.max(0, Math.floor(((iso - p.lo) / (p.hi - p.lo)) * p.counts.length)));
    out.textContent = `${formatIso(iso, this.range)}: ${p.counts[bin].toLocaleString('en-US')} blocks`;
  }
}
