// The page's GPU memory budget, in MiB, with a meter of what is held against
// it: an in-core surface's cache and vertex buffers (growth past the budget
// is refused by the pipeline with an IsosurfaceBudgetError, shown here and
// in the messages), or everything a streamed store holds (src/gpu/budget.ts:
// a lower budget frees at once).

import type { IsosurfaceBudgetError } from '../../isosurface/types.ts';
import { formatBytes } from '../format.ts';

const MiB = 2 ** 20;

/** The pipeline's default: half of the largest buffer, at most 2 GiB. */
export function defaultBudgetBytes(limits: GPUSupportedLimits): number {
  return Math.min(2 ** 31, Math.floor(limits.maxBufferSize / 2));
}

export class BudgetControl {
  private budget: number;
  private used = 0;
  private usedBy = 'used by the cache and vertex buffers';

  constructor(
    input: HTMLInputElement,
    private readonly meter: HTMLElement,
    private readonly note: HTMLElement,
    initialBytes: number,
    private readonly onChange: (bytes: number) => void,
  ) {
    this.budget = initialBytes;
    input.value = String(Math.round(initialBytes / MiB));
    input.addEventListener('change', () => {
      const mb = input.valueAsNumber;
      if (!Number.isFinite(mb) || mb < 1) {
        input.value = String(Math.round(this.budget / MiB));
        return;
      }
      this.budget = Math.round(mb * MiB);
      this.note.textContent = '';
      this.note.classList.remove('problem');
      this.render();
      this.onChange(this.budget);
    });
  }

  get bytes(): number {
    return this.budget;
  }

  /** What is held against the budget now, and by what (an in-core surface's cache and vertices; a store: everything streamed). */
  setUsed(bytes: number, by = 'used by the cache and vertex buffers'): void {
    this.used = bytes;
    this.usedBy = by;
    this.render();
  }

  showError(e: IsosurfaceBudgetError): void {
    this.note.textContent = `Needs ${formatBytes(e.neededBytes)}, the budget is ${formatBytes(e.budgetBytes)}: raise the budget to see this surface.`;
    this.note.classList.add('problem');
  }

  clearError(): void {
    if (!this.note.classList.contains('problem')) return;
    this.note.textContent = '';
    this.note.classList.remove('problem');
  }

  private render(): void {
    const f = Math.min(1, this.used / Math.max(1, this.budget));
    const fill = this.meter.firstElementChild as HTMLElement;
    fill.style.width = `${(f * 100).toFixed(1)}%`;
    this.meter.classList.toggle('high', f > 0.85);
    this.meter.title = `${formatBytes(this.used)} of ${formatBytes(this.budget)} ${this.usedBy}`;
  }
}
