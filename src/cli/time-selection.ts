// `--time SPEC` of `extract`: one time point (an integer, as before) or a
// slice `start:stop[:step]` of a store's t axis, resolved as Python resolves
// a slice against a sequence's length (`slice.indices(n)`: negative indices
// count from the end, omitted parts take their defaults, out-of-range ends
// are clamped). Pure: no store is read here.

/** A parsed slice; null parts were omitted. */
export interface TimeSlice {
  start: number | null;
  stop: number | null;
  step: number | null;
}

const SLICE = /^\s*(-?\d+)?\s*:\s*(-?\d+)?\s*(?::\s*(-?\d+)?\s*)?$/;

/** Whether the text asks for a slice (it has a colon) rather than one time point. */
export function isTimeSlice(text: string): boolean {
  return text.includes(':');
}

/** `start:stop[:step]` -> the slice; a string saying what is wrong (step 0, not a slice). */
export function parseTimeSlice(text: string): TimeSlice | string {
  const m = SLICE.exec(text);
  if (!m) return 'not a slice: give start:stop[:step] with whole numbers, any part may be omitted (0:20:2, -4:, ::-1)';
  const part = (s: string | undefined) => (s === undefined ? null : Number(s));
  const slice = { start: part(m[1]), stop: part(m[2]), step: part(m[3]) };
  if (slice.step === 0) return 'the step is 0 (a slice steps by a non-zero whole number)';
  if (![slice.start, slice.stop, slice.step].every((v) => v === null || Number.isSafeInteger(v))) return 'a part is too large';
  return slice;
}

/** The indices a slice selects from a sequence of `count` (Python's `range(*slice.indices(count))`). */
export function sliceIndices(slice: TimeSlice, count: number): number[] {
  const step = slice.step ?? 1;
  if (step === 0) throw new RangeError('slice step cannot be zero');
  // Python's rule: a negative index counts from the end; then ends are clamped to [0, count] (step > 0) or [-1, count - 1] (step < 0)
  const [lo, hi] = step > 0 ? [0, count] : [-1, count - 1];
  const resolve = (v: number | null, fallback: number) => {
    if (v === null) return fallback;
    const at = v < 0 ? v + count : v;
    return Math.min(Math.max(at, lo), hi);
  };
  const start = resolve(slice.start, step > 0 ? 0 : count - 1);
  const stop = resolve(slice.stop, step > 0 ? count : -1);
  const out: number[] = [];
  for (let i = start; step > 0 ? i < stop : i > stop; i += step) out.push(i);
  return out;
}

/** The slice as written back (`0:8:2`, `:`, `::-1`), for messages. */
export function formatTimeSlice(slice: TimeSlice): string {
  const s = (v: number | null) => (v === null ? '' : String(v));
  return `${s(slice.start)}:${s(slice.stop)}${slice.step === null ? '' : `:${slice.step}`}`;
}
