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
//
// Record plays the time points from the one on screen to the last (once, no
// loop, at the speed chosen) and records a movie of the view, one video frame
// per time point once it is whole (recorder.ts: WebM by the browser's
// MediaRecorder), with a progress bar; any other playback action cancels it;
// the file is then offered for download (STORE-tFROM-TO.webm).
import type { PrefetchState } from '../../store/series/prefetch.ts';
import { timeValueOf, type StoreTimeAxis } from '../../store/zarr/store.ts';
import { isTyping } from '../dom.ts';
import { cannotRecord, MovieRecorder, movieFileName, type ViewCapture, webmType } from './recorder.ts';

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
  /** The recording under way, else the last one (null: none yet). */
  recording: RecordingState | null;
  /** The next time point fetched ahead (null: none), and what was fetched ahead for the one on screen (null: nothing). */
  prefetch: { ahead: PrefetchState | null; shown: PrefetchState | null };
}

/** A movie of the time points (Record): its progress, then its file (no bytes: their count and the blob URL). */
export interface RecordingState {
  /** Recording now (frames are being taken). */
  active: boolean;
  /** The time points recorded: from `from` to `to`, each one video frame. */
  from: number;
  to: number;
  /** Time points recorded so far, of `toRecord`. */
  recorded: number;
  toRecord: number;
  /** Video frames handed to the recorder. */
  frames: number;
  /** The recorder's type, e.g. "video/webm;codecs=vp8", and the movie's size in pixels (the view's at the start). */
  mimeType: string | null;
  width: number;
  height: number;
  /** The file once written: its size in bytes, the blob URL its link offers and its name. */
  size: number | null;
  url: string | null;
  fileName: string | null;
  /** Why it stopped short, or why the browser cannot record (null: none). */
  message: string | null;
}

export interface PlaybackHost {
  /** The time axis of the store on screen (null: none, or no store). */
  time(): StoreTimeAxis | null;
  /**
   * Shows time point `t` (the store opened again there); true once it is on
   * screen whole, false when it was not shown (failed, superseded). `next`:
   * the time point playback asks for after it (fetched ahead meanwhile), null when none.
   */
  showTime(t: number, next: number | null): Promise<boolean>;
  /** What is fetched ahead now, and what was for the time point on screen. */
  prefetch(): { ahead: PrefetchState | null; shown: PrefetchState | null };
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
  /** Waiting for the pump to stop (a recording's start). */
  #pumped: (() => void)[] = [];
  /** The page's view, to record (setCapture). */
  #capture: ViewCapture | null = null;
  /** The movie being recorded (null: none). */
  #recorder: MovieRecorder | null = null;
  /** The recording under way or the last one. */
  #rec: RecordingState | null = null;
  /** Record was pressed and waits for the time point it starts at. */
  #recStarting = false;
  /** A prefetch line update is waiting for the next frame. */
  #prefetchPending = false;
  readonly #els: {
    toggle: HTMLButtonElement;
    back: HTMLButtonElement;
    forward: HTMLButtonElement;
    loop: HTMLInputElement;
    fps: HTMLSelectElement;
    slider: HTMLInputElement;
    label: HTMLElement;
    rate: HTMLElement;
    prefetch: HTMLElement;
    record: HTMLButtonElement;
    progress: HTMLProgressElement;
    recordStatus: HTMLElement;
    file: HTMLAnchorElement;
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
      `<p class="playback-rate" data-k="playback-rate"></p>` +
      `<p class="playback-prefetch" data-k="playback-prefetch"></p>` +
      `<p class="playback-record"><button type="button" data-play="record" title="play from this time point to the last and record the view as a WebM movie, one frame per time point">● record</button> ` +
      `<progress data-k="record-progress" max="1" value="0" hidden></progress> <span data-k="record-status"></span> ` +
      `<a data-k="record-file" hidden></a></p>`;
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
      prefetch: q('[data-k="playback-prefetch"]'),
      record: q('[data-play="record"]'),
      progress: q('[data-k="record-progress"]'),
      recordStatus: q('[data-k="record-status"]'),
      file: q('[data-k="record-file"]'),
    };
    this.element = box;
    const e = this.#els;
    e.toggle.addEventListener('click', () => this.toggle());
    e.back.addEventListener('click', () => this.step(-1));
    e.forward.addEventListener('click', () => this.step(1));
    e.record.addEventListener('click', () => void this.record());
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
      recording: this.#rec ? { ...this.#rec } : null,
      prefetch: this.host.prefetch(),
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
      if (this.#recorder) void this.#stopRecording('Recording cancelled: the series is no longer on screen.');
    }
    this.#update();
  }

  /** The prefetch of the next time point moved on (a chunk arrived, started, taken): its line. */
  prefetchChanged(): void {
    if (this.#prefetchPending) return;
    // at most one panel update per frame: chunks arrive by the hundred
    this.#prefetchPending = true;
    requestAnimationFrame(() => {
      this.#prefetchPending = false;
      this.#update();
    });
  }

  /** The page's view, which Record films. */
  setCapture(capture: ViewCapture): void {
    this.#capture = capture;
  }

  get recording(): boolean {
    return this.#recorder !== null;
  }

  /**
   * Record (or, while recording, cancel): plays from the time point on
   * screen (at the last one, from the first) to the last, once, and records
   * one video frame of the view per time point once it is whole; then offers
   * the WebM file.
   */
  async record(): Promise<void> {
    if (this.#recorder) {
      void this.#stopRecording('Recording cancelled.');
      return;
    }
    if (this.#recStarting) return;
    const why = cannotRecord(this.#capture);
    let axis = this.host.time();
    if (why || !axis || axis.count <= 1) {
      if (why) this.#rec = this.#emptyRecording(0, 0, why);
      this.#update();
      return;
    }
    this.pause();
    this.#target = null;
    this.#recStarting = true;
    let from = 0;
    try {
      await this.#whenPumped();
      axis = this.host.time();
      if (!axis || axis.count <= 1 || this.#recorder || this.#playing) return;
      from = axis.index === axis.count - 1 ? 0 : axis.index;
      if (axis.index !== from) {
        this.go(from);
        await this.#whenPumped();
        if (this.host.time()?.index !== from || this.#recorder || this.#playing) return;
      }
    } finally {
      this.#recStarting = false;
    }
    const to = axis.count - 1;
    this.#clearFile();
    const mimeType = webmType()!;
    let recorder: MovieRecorder;
    try {
      recorder = new MovieRecorder(this.#capture!, mimeType);
    } catch (e) {
      this.#rec = this.#emptyRecording(from, to, `This browser cannot record the view: ${(e as Error).message}`);
      this.#update();
      return;
    }
    this.#recorder = recorder;
    this.#rec = {
      ...this.#emptyRecording(from, to, null),
      active: true,
      mimeType: recorder.mimeType,
      width: recorder.width,
      height: recorder.height,
    };
    this.#update();
    // the time point on screen is the first frame, then each one played
    await this.#recordFrame(from);
    if (this.#recorder !== recorder) return;
    this.#playing = true;
    this.#arrivals = [];
    this.#update();
    void this.#pump();
  }

  /** A frame of the movie: time point `t`, on screen whole now. */
  async #recordFrame(t: number): Promise<void> {
    const recorder = this.#recorder;
    const rec = this.#rec;
    if (!recorder || !rec || t !== rec.from + rec.recorded) return;
    await recorder.frame();
    if (this.#recorder !== recorder) return;
    rec.recorded++;
    rec.frames = recorder.frames;
    this.#update();
  }

  /** The recording ends: written whole (the file offered), or cut short with `message` (dropped). */
  async #stopRecording(message: string | null): Promise<void> {
    const recorder = this.#recorder;
    const rec = this.#rec;
    if (!recorder || !rec) return;
    this.#recorder = null;
    rec.active = false;
    if (message !== null || rec.recorded < rec.toRecord) {
      recorder.cancel();
      rec.message = message ?? `Recording stopped at t = ${rec.from + rec.recorded}: the time point was not shown.`;
      this.#update();
      return;
    }
    this.#update();
    try {
      const blob = await recorder.finish();
      if (this.#rec !== rec) return;
      rec.size = blob.size;
      rec.url = URL.createObjectURL(blob);
      rec.fileName = movieFileName(storeName(), rec.from, rec.to);
    } catch (e) {
      if (this.#rec === rec) rec.message = `The recording failed: ${(e as Error).message}`;
    }
    this.#update();
  }

  #emptyRecording(from: number, to: number, message: string | null): RecordingState {
    return {
      active: false,
      from,
      to,
      recorded: 0,
      toRecord: to - from + 1,
      frames: 0,
      mimeType: null,
      width: 0,
      height: 0,
      size: null,
      url: null,
      fileName: null,
      message,
    };
  }

  /** The last recording's file is let go (a new recording). */
  #clearFile(): void {
    if (this.#rec?.url) URL.revokeObjectURL(this.#rec.url);
    this.#rec = null;
  }

  #whenPumped(): Promise<void> {
    return this.#pumping ? new Promise((resolve) => this.#pumped.push(resolve)) : Promise.resolve();
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
    if (this.#recorder) void this.#stopRecording('Recording cancelled.');
    if (!this.#playing) return;
    this.#playing = false;
    this.#wake?.();
    this.#update();
  }

  toggle(): void {
    if (this.#playing || this.#recorder) this.pause();
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
        // the one after is fetched ahead (playing, or a step forward likely followed by another)
        const shown = await this.host.showTime(next, this.#following(next));
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
        if (playing && this.#playing && this.#recorder) await this.#recordFrame(next);
        if (playing && this.#playing) {
          this.#arrivals.push(performance.now());
          if (this.#arrivals.length > RATE_WINDOW + 1) this.#arrivals.shift();
        }
        if (this.#asked === next && this.#target === null) this.#asked = null;
        this.#update();
      }
    } finally {
      this.#pumping = false;
      // a recording's last time point recorded (or one not shown): its end
      if (this.#recorder && !this.#playing) void this.#stopRecording(null);
      const waiting = this.#pumped;
      this.#pumped = [];
      for (const resolve of waiting) resolve();
      this.#update();
    }
  }

  /** The time point playing asks for after `t` (none past the end without loop, nor after a recording's last). */
  #following(t: number): number | null {
    const axis = this.host.time();
    if (!axis || axis.count <= 1) return null;
    if (t + 1 < axis.count) return t + 1;
    return this.#loop && !this.#recorder ? 0 : null;
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
    // a recording plays once
    if (this.#loop && !this.#recorder) return 0;
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
      e.prefetch.textContent = prefetchLine(this.host.prefetch());
      const pf = this.host.prefetch();
      e.prefetch.classList.toggle('behind', !!(pf.ahead ?? pf.shown)?.full);
    }
    this.#showRecording();
    this.host.changed();
  }

  /** The Record button, the progress bar, the message and the file's link. */
  #showRecording(): void {
    const e = this.#els;
    const r = this.#rec;
    const on = this.#recorder !== null;
    e.record.textContent = on ? '■ cancel' : '● record';
    e.record.dataset.state = on ? 'recording' : 'idle';
    e.record.setAttribute('aria-label', on ? 'cancel the recording' : 'record a movie');
    e.progress.hidden = !on;
    if (r && on) {
      e.progress.max = r.toRecord;
      e.progress.value = r.recorded;
    }
    e.recordStatus.textContent = !r
      ? ''
      : on
        ? `recording: ${r.recorded} of ${r.toRecord} time points`
        : (r.message ?? (r.url ? '' : 'writing the movie…'));
    e.recordStatus.classList.toggle('error', !on && !!r?.message);
    const file = !on && r?.url && r.fileName ? r : null;
    e.file.hidden = !file;
    if (file) {
      e.file.href = file.url!;
      e.file.download = file.fileName!;
      e.file.textContent = `download ${file.fileName} (${(file.size! / 1024).toFixed(0)} KiB, ${file.recorded} frames, ${file.width}×${file.height})`;
    } else e.file.removeAttribute('href');
  }
}

/** The store on screen's name as the page shows it (its URL or folder / file name). */
function storeName(): string | undefined {
  return (window as unknown as { zfpisoStore?: { url?: string } }).zfpisoStore?.url;
}

/**
 * The panel's line on what is fetched ahead: the next time point's chunks
 * there, else what was fetched ahead for the one on screen; and when the
 * bound held only part of it (the rest came when it was shown).
 */
export function prefetchLine(p: { ahead: PrefetchState | null; shown: PrefetchState | null }): string {
  const a = p.ahead ?? p.shown;
  if (!a) return '';
  const mb = (b: number) => `${(b / 2 ** 20).toFixed(2)} MiB`;
  if (a.error) return `t = ${a.time} not fetched ahead: ${a.error}`;
  if (p.ahead && a.wanted === 0 && !a.done) return `fetching t = ${a.time} ahead…`;
  const part = a.full
    ? ` — only ${a.asked} of ${a.wanted} fit the ${mb(a.capacityBytes)} prefetch bound, the rest is fetched when shown`
    : '';
  const head = p.ahead ? `t = ${a.time} ahead: ${a.arrived} of ${a.asked} chunks` : `t = ${a.time} was fetched ahead: ${a.arrived} chunks`;
  return `${head}, ${mb(a.bytes)}${p.ahead && a.done ? ' (ready)' : ''}${part}`;
}
