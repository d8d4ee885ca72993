// Playback of a store's time points (issue 47): play / pause, step back and
// forward, loop, speed (as fast as time points arrive, or 1, 2, 5, 10 per
// second), a time slider with the index and, when the OME metadata give a
// scale along t, the physical time and unit. Space plays and pauses, Alt+←
// and Alt+→ step (not while typing in a field). Each time point is the store
// opened again at that index through the store view's one reopen path
// (StoreView.showTime: isovalue, camera, clip, surfaces and refinement
// kept); the next one is asked for only once the one on screen is whole (its
// refinement ended), and the one before stays drawn until then. At a fixed
// speed the rest of the frame interval is waited; the achieved rate is shown,
// with "falling behind" when it is below the one asked.
import { timeValueOf, type StoreTimeAxis } from '../../store/zarr/store.ts';
import { isTyping } from '../dom.ts';

/** What the page tests read (window.zfpisoStore.playback). */
export interface PlaybackState {
  /** The time point on screen and how many there are. */
  index: number;
  count: number;
  playing: boolean;
  loop: boolean;
  /** Time points per second asked for; 0: as fast as they arrive. */
  fps: number;
  /** Time points per second shown while playing (over the last few), null before two were shown. */
  achievedFps: number | null;
  /** Playing at a fixed speed and the achieved rate is below it. */
  behind: boolean;
  /** Time points shown by playback or steps since the page opened. */
  framesShown: number;
  /** A time point is on its way (asked for, not yet whole on screen), or the interval before the next is waited. */
  busy: boolean;
}

export interface PlaybackHost {
  /** The time axis of the store on screen (null: none, or no store). */
  time(): StoreTimeAxis | null;
  /** Shows time point `t` (the store opened again there); true once it is on screen whole, false when it was not shown (failed, superseded). */
  showTime(t: number): Promise<boolean>;
  /** The playback's state changed (the panel's figures and window.zfpisoStore). */
  changed(): void;
}

export const PLAYBACK_SPEEDS = [0, 1, 2, 5, 10] as const;
/** Intervals between time points shown that the achieved rate is taken over. */
const RATE_WINDOW = 5;
/** Below this share of the speed asked for, playback says it falls behind. */
const BEHIND = 0.9;

export class Playback {
  readonly element: HTMLElement;
  #playing = false;
  #loop = false;
  #fps = 0;
  /** A step or the slider asked for this time point (newest wins); the pump shows it next. */
  #target: number | null = null;
  #pumping = false;
  /** When the time points shown while playing arrived (performance.now()), the last few. */
  #arrivals: number[] = [];
  #framesShown = 0;
  /** The time point asked for last (shown or on its way): the slider's position. */
  #asked: number | null = null;
  /** The waiting of the frame interval (cut short by pause). */
  #wake: (() => void) | null = null;
  readonly #els: {
    toggle: HTMLButtonElement;
    back: HTMLButtonElement;
    forward: HTMLButtonElement;
    loop: HTMLInputElement;
    fps: HTMLSelectElement;
    slider: HTMLInputElement;
    label: HTMLElement;
    rate: HTMLElement;
  };

  constructor(private readonly host: PlaybackHost) {
    const box = document.createElement('div');
    box.className = 'store-playback';
    box.id = 'store-playback';
    box.hidden = true;
    box.innerHTML =
      `<p class="playback-buttons">` +
      `<button type="button" data-play="back" title="step back (Alt+←)" aria-label="step back">|◀</button> ` +
      `<button type="button" data-play="toggle" title="play / pause (Space)" aria-label="play">▶</button> ` +
      `<button type="button" data-play="forward" title="step forward (Alt+→)" aria-label="step forward">▶|</button> ` +
      `<label title="after the last time point, the first"><input type="checkbox" data-play="loop"> loop</label></p>` +
      `<p class="playback-speed"><label>speed <select data-play="fps">${PLAYBACK_SPEEDS.map(
        (f) => `<option value="${f}">${f === 0 ? 'as fast as it arrives' : `${f} fps`}</option>`,
      ).join('')}</select></label></p>` +
      `<p class="playback-time"><input type="range" data-play="time" min="0" max="0" step="1" value="0" aria-label="time point"> ` +
      `<span data-k="time"></span></p>` +
      `<p class="playback-rate" data-k="playback-rate"></p>`;
    const q = <T extends HTMLElement>(sel: string) => box.querySelector(sel) as T;
    this.#els = {
      toggle: q('[data-play="toggle"]'),
      back: q('[data-play="back"]'),
      forward: q('[data-play="forward"]'),
      loop: q('[data-play="loop"]'),
      fps: q('[data-play="fps"]'),
      slider: q('[data-play="time"]'),
      label: q('[data-k="time"]'),
      rate: q('[data-k="playback-rate"]'),
    };
    this.element = box;
    const e = this.#els;
    e.toggle.addEventListener('click', () => this.toggle());
    e.back.addEventListener('click', () => this.step(-1));
    e.forward.addEventListener('click', () => this.step(1));
    e.loop.addEventListener('change', () => {
      this.#loop = e.loop.checked;
      this.#update();
    });
    e.fps.addEventListener('change', () => {
      this.#fps = Number(e.fps.value) || 0;
      this.#arrivals = [];
      this.#update();
    });
    // while dragged the label follows; the time point opens on release (or a key), not at every position passed
    e.slider.addEventListener('input', () => this.#label(Number(e.slider.value)));
    e.slider.addEventListener('change', () => {
      this.pause();
      this.go(Number(e.slider.value));
    });
    // capture: Alt+arrows before the isovalue slider's own arrows, when a series is on screen
    window.addEventListener('keydown', (ev) => this.#key(ev), { capture: true });
  }

  get state(): PlaybackState {
    const axis = this.host.time();
    const achieved = this.#achieved();
    return {
      index: axis?.index ?? 0,
      count: axis?.count ?? 0,
      playing: this.#playing,
      loop: this.#loop,
      fps: this.#fps,
      achievedFps: achieved,
      behind: this.#behind(achieved),
      framesShown: this.#framesShown,
      busy: this.#pumping,
    };
  }

  get playing(): boolean {
    return this.#playing;
  }

  /** A store is on screen (another time point of the same, or another store): the controls follow its time axis. */
  storeShown(): void {
    const axis = this.host.time();
    if (!axis || axis.count <= 1) {
      this.#playing = false;
      this.#target = null;
      this.#asked = null;
    }
    this.#update();
  }

  play(): void {
    const axis = this.host.time();
    if (!axis || axis.count <= 1 || this.#playing) return;
    this.#playing = true;
    this.#arrivals = [];
    // at the end without loop, play starts again from the first time point (as video players do)
    if (!this.#loop && axis.index === axis.count - 1 && this.#target === null) this.#target = 0;
    this.#update();
    void this.#pump();
  }

  pause(): void {
    if (!this.#playing) return;
    this.#playing = false;
    this.#wake?.();
    this.#update();
  }

  toggle(): void {
    if (this.#playing) this.pause();
    else this.play();
  }

  /** One time point back or forward (playback pauses); wraps with loop, else stops at either end. */
  step(by: number): void {
    const axis = this.host.time();
    if (!axis || axis.count <= 1) return;
    this.pause();
    const from = this.#asked ?? axis.index;
    let t = from + by;
    if (this.#loop) t = ((t % axis.count) + axis.count) % axis.count;
    else t = Math.min(axis.count - 1, Math.max(0, t));
    if (t !== from) this.go(t);
  }

  /** Shows time point `t` (the newest asked wins; the one on its way finishes first). */
  go(t: number): void {
    const axis = this.host.time();
    if (!axis || !Number.isInteger(t) || t < 0 || t >= axis.count) return;
    this.#target = t;
    this.#asked = t;
    this.#update();
    void this.#pump();
  }

  /** Shows the asked time points, and while playing the next ones, one at a time: each only once the one before is whole. */
  async #pump(): Promise<void> {
    if (this.#pumping) return;
    this.#pumping = true;
    try {
      for (;;) {
        let next = this.#target;
        this.#target = null;
        if (next === null && this.#playing) next = this.#nextPlayed();
        if (next === null) break;
        const playing = this.#playing;
        if (playing && this.#fps > 0 && this.#arrivals.length > 0) {
          // the rest of this frame's interval
          const wait = 1000 / this.#fps - (performance.now() - this.#arrivals[this.#arrivals.length - 1]);
          if (wait > 0) await this.#sleep(wait);
          // paused, or a step asked for meanwhile: that decides
          if (!this.#playing || this.#target !== null) {
            if (this.#target === null && !this.#playing) break;
            continue;
          }
        }
        this.#asked = next;
        this.#update();
        const shown = await this.host.showTime(next);
        if (!shown) {
          // not shown (failed, or another store opened): playback stops there
          if (this.host.time()?.index !== next) {
            this.#playing = false;
            this.#asked = null;
            this.#update();
            if (this.#target === null) break;
          }
          continue;
        }
        this.#framesShown++;
        if (playing && this.#playing) {
          this.#arrivals.push(performance.now());
          if (this.#arrivals.length > RATE_WINDOW + 1) this.#arrivals.shift();
        }
        if (this.#asked === next && this.#target === null) this.#asked = null;
        this.#update();
      }
    } finally {
      this.#pumping = false;
      this.#update();
    }
  }

  /** While playing: the time point after the one on screen; at the end, the first with loop, else playback stops. */
  #nextPlayed(): number | null {
    const axis = this.host.time();
    if (!axis || axis.count <= 1) {
      this.#playing = false;
      return null;
    }
    const t = axis.index + 1;
    if (t < axis.count) return t;
    if (this.#loop) return 0;
    this.#playing = false;
    this.#update();
    return null;
  }

  #sleep(ms: number): Promise<void> {
    return new Promise((resolve) => {
      const timer = setTimeout(done, ms);
      function done() {
        clearTimeout(timer);
        resolve();
      }
      this.#wake = () => {
        this.#wake = null;
        done();
      };
    });
  }

  /** Time points per second over the last few shown while playing. */
  #achieved(): number | null {
    const a = this.#arrivals;
    if (a.length < 2) return null;
    const span = a[a.length - 1] - a[0];
    return span > 0 ? ((a.length - 1) * 1000) / span : null;
  }

  #behind(achieved: number | null): boolean {
    return this.#playing && this.#fps > 0 && achieved !== null && achieved < this.#fps * BEHIND;
  }

  #key(e: KeyboardEvent): void {
    if (e.defaultPrevented || e.ctrlKey || e.metaKey || this.element.hidden) return;
    const axis = this.host.time();
    if (!axis || axis.count <= 1 || isTyping(e.target) || document.querySelector('dialog[open]')) return;
    if (e.key === ' ' && !e.altKey && !e.shiftKey) {
      // a focused button or checkbox takes Space as its own click
      const t = e.target;
      if (t instanceof HTMLButtonElement || (t instanceof HTMLInputElement && (t.type === 'checkbox' || t.type === 'radio'))) return;
      this.toggle();
    } else if (e.altKey && !e.shiftKey && (e.key === 'ArrowLeft' || e.key === 'ArrowRight')) {
      this.step(e.key === 'ArrowLeft' ? -1 : 1);
    } else return;
    e.preventDefault();
    e.stopPropagation();
  }

  /** The label: the index (of how many) and, when the metadata give a step along t, the time and unit. */
  #label(t: number): void {
    const axis = this.host.time();
    if (!axis) return;
    const value = timeValueOf(axis, t);
    const time = value === null ? '' : ` (${Number(value.toPrecision(6))}${axis.unit ? ` ${axis.unit}` : ''})`;
    this.#els.label.textContent = `t = ${t} of ${axis.count}${time}`;
  }

  #update(): void {
    const axis = this.host.time();
    const e = this.#els;
    const on = !!axis && axis.count > 1;
    this.element.hidden = !on;
    if (on) {
      e.slider.max = String(axis.count - 1);
      // the slider is not moved under the user's hand (while it has focus it shows what was asked last)
      const at = this.#asked ?? axis.index;
      if (document.activeElement !== e.slider || !this.#pumping) e.slider.value = String(at);
      this.#label(at);
      e.toggle.textContent = this.#playing ? '❙❙' : '▶';
      e.toggle.setAttribute('aria-label', this.#playing ? 'pause' : 'play');
      e.toggle.dataset.state = this.#playing ? 'playing' : 'paused';
      const achieved = this.#achieved();
      const behind = this.#behind(achieved);
      e.rate.textContent =
        this.#playing || achieved !== null
          ? `${achieved === null ? '…' : achieved.toFixed(1)} time points/s${this.#fps > 0 ? ` of ${this.#fps} asked` : ''}${behind ? ' — falling behind' : ''}`
          : '';
      e.rate.classList.toggle('behind', behind);
    }
    this.host.changed();
  }
}
