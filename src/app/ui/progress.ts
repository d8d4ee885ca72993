// The progress card over the view while a volume loads: what, which step,
// how far (a bar when the fraction is known, a moving stripe otherwise), and
// Cancel.

export class ProgressView {
  private readonly title: HTMLElement;
  private readonly phase: HTMLElement;
  private readonly bar: HTMLElement;
  private readonly fill: HTMLElement;
  private onCancel: (() => void) | undefined;
  private startedAt = 0;
  private timer: ReturnType<typeof setInterval> | undefined;
  private phaseText = '';

  constructor(private readonly root: HTMLElement) {
    this.title = root.querySelector('.progress-title')!;
    this.phase = root.querySelector('.progress-phase')!;
    this.bar = root.querySelector('.progress-bar')!;
    this.fill = this.bar.firstElementChild as HTMLElement;
    root.querySelector('.progress-cancel')!.addEventListener('click', () => this.onCancel?.());
  }

  start(title: string, onCancel: () => void): void {
    this.title.textContent = title;
    this.onCancel = onCancel;
    this.root.hidden = false;
    this.startedAt = performance.now();
    clearInterval(this.timer);
    // Long GPU steps (SwiftShader) show the elapsed time so the page never looks stuck.
    this.timer = setInterval(() => this.renderPhase(), 500);
    this.set('Starting…');
  }

  /** fraction in [0, 1], or undefined when unknown (indeterminate). */
  set(phase: string, fraction?: number): void {
    this.phaseText = phase;
    this.renderPhase();
    const known = fraction !== undefined && Number.isFinite(fraction);
    this.bar.classList.toggle('indeterminate', !known);
    this.fill.style.width = known ? `${Math.round(Math.min(1, Math.max(0, fraction)) * 100)}%` : '';
    this.root.dataset.phase = phase;
  }

  private renderPhase(): void {
    const s = (performance.now() - this.startedAt) / 1000;
    this.phase.textContent = s >= 2 ? `${this.phaseText} (${s.toFixed(0)} s)` : this.phaseText;
  }

  finish(): void {
    clearInterval(this.timer);
    this.timer = undefined;
    this.onCancel = undefined;
    this.root.hidden = true;
  }
}
