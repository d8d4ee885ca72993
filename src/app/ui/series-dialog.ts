// The small dialog that asks, when the names of several dropped files do not
// say it for sure, whether they are a time series: "Open these N files as a
// time series / Open the first only / Cancel". Made in the page on first
// use (the style of the volume form: Enter takes the series, Escape cancels).

export type SeriesAnswer = 'series' | 'first' | 'cancel';

export class SeriesDialog {
  #dialog: HTMLDialogElement | null = null;
  #resolve: ((a: SeriesAnswer) => void) | undefined;

  get isOpen(): boolean {
    return this.#dialog?.open ?? false;
  }

  /** Asks about `count` files from `first` to `last` (time order as shown), saying why the names leave it open. */
  ask(count: number, first: string, last: string, why: string): Promise<SeriesAnswer> {
    this.#close('cancel');
    const d = this.#make();
    d.querySelector('.form-file')!.textContent = `${first} … ${last}`;
    d.querySelector('.series-why')!.textContent = `Not sure from the names: ${why}. In time order, they run from ${first} to ${last}.`;
    d.querySelector('[data-answer="series"]')!.textContent = `Open these ${count} files as a time series`;
    d.showModal();
    d.querySelector<HTMLButtonElement>('[data-answer="series"]')!.focus();
    return new Promise((resolve) => (this.#resolve = resolve));
  }

  /** Closes the dialog as if cancelled (another drop came). */
  cancel(): void {
    this.#close('cancel');
  }

  #close(a: SeriesAnswer): void {
    if (this.#dialog?.open) this.#dialog.close();
    const resolve = this.#resolve;
    this.#resolve = undefined;
    resolve?.(a);
  }

  #make(): HTMLDialogElement {
    if (this.#dialog) return this.#dialog;
    const d = document.createElement('dialog');
    d.id = 'series-dialog';
    d.setAttribute('aria-labelledby', 'series-dialog-title');
    d.innerHTML = `
      <form method="dialog">
        <h3 id="series-dialog-title">A time series?</h3>
        <p class="form-file"></p>
        <p class="series-why"></p>
        <div class="form-buttons">
          <button type="button" data-answer="cancel">Cancel</button>
          <button type="button" data-answer="first">Open the first only</button>
          <button type="submit" class="primary" data-answer="series"></button>
        </div>
      </form>`;
    d.querySelector('form')!.addEventListener('submit', (e) => {
      e.preventDefault();
      this.#close('series');
    });
    for (const b of d.querySelectorAll<HTMLButtonElement>('button[type="button"]'))
      b.addEventListener('click', () => this.#close(b.dataset.answer as SeriesAnswer));
    // Escape (the dialog's cancel event) cancels
    d.addEventListener('cancel', (e) => {
      e.preventDefault();
      this.#close('cancel');
    });
    document.body.append(d);
    this.#dialog = d;
    return d;
  }
}
