// One GPU memory budget for everything a page (or a CLI run) streams: the
// limit, what is held against it (counted where it is made: a meter, or a
// CPU stand-in's count in tests), and who is told when the limit changes.
// Every store stream, its surfaces, drawn copies and readbacks allocate
// against the one object, so "never over the budget" holds across budget
// changes, store switches and closes, not only inside one stream.
import { GpuMemoryMeter } from './memory-meter.ts';

export type BudgetListener = (bytes: number, previous: number) => void;

export class GpuBudget {
  #bytes: number;
  readonly #listeners = new Set<BudgetListener>();

  /**
   * `held`: bytes held against the budget now (default: the meter's). A
   * store's own meter is made a child of `meter` (memory-meter.ts), so the
   * budget sees every store's buffers.
   */
  constructor(
    bytes: number,
    readonly meter: GpuMemoryMeter = new GpuMemoryMeter(),
    readonly held: () => number = () => meter.bytes,
  ) {
    if (!(bytes >= 0)) throw new RangeError(`GPU memory budget must be a number of bytes (got ${bytes})`);
    this.#bytes = bytes;
  }

  /** The limit, bytes. */
  get bytes(): number {
    return this.#bytes;
  }

  /**
   * A new limit: every listener is told (a lower limit frees at once, in the
   * listeners), then the peak starts again from what is held.
   */
  set bytes(next: number) {
    if (!(next >= 0)) throw new RangeError(`GPU memory budget must be a number of bytes (got ${next})`);
    const previous = this.#bytes;
    if (next === previous) return;
    this.#bytes = next;
    for (const l of [...this.#listeners]) l(next, previous);
    this.meter.resetPeak();
  }

  /** Bytes held against the budget now. */
  get heldBytes(): number {
    return this.held();
  }

  onChange(l: BudgetListener): () => void {
    this.#listeners.add(l);
    return () => this.#listeners.delete(l);
  }
}
