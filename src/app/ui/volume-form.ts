// The small form that asks what a file's name does not say: the shape and
// sample type of a raw volume, the rate of a header-less zfp stream, and the
// rate raw and NRRD volumes are compressed at. Prefilled from the name;
// Enter opens, Escape cancels (the current volume stays).

import { DTYPE_BYTES, isDType, type DType } from '../../core/dtype.ts';
import type { Dims } from '../../core/naming.ts';
import type { OpenRequest, VolumeFileFacts } from '../../volume/open-volume.ts';
import { blockGridOf, fixedRateStreamBytes } from '../../zfp/format.ts';
import { formatBytes } from '../format.ts';

export class VolumeForm {
  private readonly form: HTMLFormElement;
  private resolve: ((r: OpenRequest | undefined) => void) | undefined;
  private facts: VolumeFileFacts | undefined;

  constructor(private readonly dialog: HTMLDialogElement) {
    this.form = dialog.querySelector('form')!;
    this.form.addEventListener('input', () => this.check());
    this.form.addEventListener('submit', (e) => {
      e.preventDefault();
      const r = this.read();
      if (r) this.close(r);
    });
    dialog.querySelector('.form-cancel')!.addEventListener('click', () => this.close(undefined));
    // Escape (the dialog's cancel event) and closing by any other means cancel.
    dialog.addEventListener('cancel', (e) => {
      e.preventDefault();
      this.close(undefined);
    });
  }

  get isOpen(): boolean {
    return this.dialog.open;
  }

  /** Asks for what `facts` lacks (and the rate for compression); undefined when cancelled. */
  ask(facts: VolumeFileFacts): Promise<OpenRequest | undefined> {
    this.resolve?.(undefined);
    this.facts = facts;
    const f = this.form;
    const q = <T extends Element>(s: string) => f.querySelector(s) as T;
    const title = facts.compresses ? 'Compress on the GPU' : 'Open a header-less zfp stream';
    q<HTMLElement>('#volume-form-title').textContent = title;
    q<HTMLElement>('.form-file').textContent = `${facts.fileName} (${formatBytes(facts.bytes)})`;
    const dimsEditable = facts.missing.includes('dims') || facts.kind === 'raw';
    const dtypeShown = facts.compresses;
    const dtypeEditable = facts.kind === 'raw';
    for (const [i, n] of ['nx', 'ny', 'nz'].entries()) {
      const input = f.elements.namedItem(n) as HTMLInputElement;
      input.value = facts.dims ? String(facts.dims[i]) : '';
      input.disabled = !dimsEditable;
    }
    const dtype = f.elements.namedItem('dtype') as HTMLSelectElement;
    dtype.value = facts.dtype ?? 'uint8';
    dtype.disabled = !dtypeEditable;
    q<HTMLElement>('.field-dtype').hidden = !dtypeShown;
    const rate = f.elements.namedItem('rate') as HTMLInputElement;
    // Volumes compressed here: empty means the rate chosen from the data (src/zfp/rate-choice.ts).
    rate.value = facts.compresses ? '' : String(facts.rate ?? facts.fittingRates?.[0] ?? '');
    rate.placeholder = facts.compresses ? 'from the data' : '';
    rate.required = !facts.compresses;
    q<HTMLElement>('.form-ok').textContent = facts.compresses ? 'Compress and open' : 'Open';
    this.check();
    this.dialog.showModal();
    const first = [...f.querySelectorAll<HTMLInputElement>('input:not([disabled])')].find((i) => i.value === '');
    (first ?? q<HTMLButtonElement>('.form-ok')).focus();
    return new Promise((resolve) => (this.resolve = resolve));
  }

  private values(): { dims?: Dims; dtype?: DType; rate?: number } {
    const f = this.form;
    const num = (n: string) => Number((f.elements.namedItem(n) as HTMLInputElement).value);
    const d = [num('nx'), num('ny'), num('nz')];
    const dims = d.every((v) => Number.isInteger(v) && v >= 1) ? (d as Dims) : undefined;
    const t = (f.elements.namedItem('dtype') as HTMLSelectElement).value;
    const r = num('rate');
    return { dims, dtype: isDType(t) ? t : undefined, rate: Number.isFinite(r) && r > 0 ? r : undefined };
  }

  /** Live check of the entries against the file size; returns the request when valid. */
  private check(): OpenRequest | undefined {
    const facts = this.facts;
    if (!facts) return undefined;
    const { dims, dtype, rate } = this.values();
    const out = this.form.querySelector('.form-check') as HTMLElement;
    const ok = this.form.querySelector('.form-ok') as HTMLButtonElement;
    let problem: string | undefined;
    let note = '';
    if (!dims) problem = 'Enter the three dimensions.';
    else if (!rate && !facts.compresses) problem = 'Enter a rate (bits per value), e.g. 8.';
    else if (rate !== undefined && (rate < 0.25 || rate > 64)) problem = 'The rate must be between 0.25 and 64 bits per value.';
    else {
      const g = blockGridOf(dims);
      const blocks = g[0] * g[1] * g[2];
      const streamBytes = rate === undefined ? 0 : fixedRateStreamBytes(blocks, Math.floor(64 * rate + 0.5));
      if (facts.compresses) {
        const t = dtype ?? 'uint8';
        const expect =
          facts.kind === 'nrrd'
            ? facts.nrrd!.data.byteLength
            : facts.kind === 'tiff'
              ? facts.samples!.byteLength
              : dims[0] * dims[1] * dims[2] * DTYPE_BYTES[t];
        if (facts.kind === 'raw' && expect !== facts.bytes) {
          problem = `${dims.join(' × ')} ${t} is ${expect.toLocaleString('en-US')} bytes; the file has ${facts.bytes.toLocaleString('en-US')}.`;
        } else {
          note =
            rate === undefined
              ? `${formatBytes(expect)} → the GPU, at the smallest rate that keeps surfaces faithful (tried on a sample of the data)`
              : `${formatBytes(expect)} → ${formatBytes(streamBytes)} on the GPU (${(expect / streamBytes).toFixed(1)} : 1)`;
        }
      } else if (streamBytes !== facts.bytes) {
        const fits = facts.fittingRates?.length ? ` The size fits rate ${facts.fittingRates.join(' or ')}.` : '';
        problem = `A ${dims.join(' × ')} stream at rate ${rate} is ${streamBytes.toLocaleString('en-US')} bytes; the file has ${facts.bytes.toLocaleString('en-US')}.${fits}`;
      } else {
        note = `${dims.join(' × ')} float32, ${blocks.toLocaleString('en-US')} blocks of ${Math.floor(64 * (rate ?? 0) + 0.5)} bits`;
      }
    }
    out.textContent = problem ?? note;
    out.classList.toggle('problem', problem !== undefined);
    ok.disabled = problem !== undefined;
    if (problem) return undefined;
    return { dims, dtype: facts.compresses ? dtype : undefined, rate };
  }

  private read(): OpenRequest | undefined {
    return this.check();
  }

  private close(r: OpenRequest | undefined): void {
    if (this.dialog.open) this.dialog.close();
    const resolve = this.resolve;
    this.resolve = undefined;
    this.facts = undefined;
    resolve?.(r);
  }

  /** Closes the form as if cancelled (another load started). */
  cancel(): void {
    this.close(undefined);
  }
}
