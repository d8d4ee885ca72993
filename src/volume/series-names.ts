// Whether a set of dropped file names reads as a time series, and in which
// order: numbered names (the same text around one run of digits that differs
// from file to file: step_000.raw .. step_019.raw, t1.tif .. t12.tif) sorted
// by that number, not by the text. Names that say less (numbers with gaps,
// two runs of digits that differ, no number at all) give an order too, with
// the reason the page should ask before taking them as a series. Pure: names
// in, order out (file-series.ts in the page does the asking and the reading).

/** The kinds of file a series is made of (each file one 3-D volume of the same shape). */
export type SeriesFileKind = 'raw' | 'nrrd' | 'tiff';

/** The kind of a file by its extension (`.raw`, `.nrrd`, `.tif` / `.tiff`), or null. */
export function seriesKindOfName(name: string): SeriesFileKind | null {
  const lower = name.toLowerCase();
  if (lower.endsWith('.raw')) return 'raw';
  if (lower.endsWith('.nrrd')) return 'nrrd';
  if (/\.tiff?$/.test(lower)) return 'tiff';
  return null;
}

/** The one kind every name has, or null (mixed extensions, or a kind a series cannot be made of). */
export function seriesKindOf(names: readonly string[]): SeriesFileKind | null {
  const kinds = new Set(names.map(seriesKindOfName));
  if (kinds.size !== 1) return null;
  return [...kinds][0];
}

export interface SeriesOrder {
  /** Indices into the names given, in time order. */
  order: number[];
  /** The names say it: one run of digits differs, every number once, evenly spaced. */
  sure: boolean;
  /** When not sure: why, in words the page shows before asking. */
  why?: string;
  /** The numbers of the run that differs, in time order (numbered names only). */
  numbers?: number[];
}

/**
 * Text and digit runs of a name: ['step_', '007', '.raw'] (digits at odd
 * indices). A shape in the name (`_48x48x48`) is text: files of another
 * shape are the same series' files, refused for their shape, not unnumbered.
 */
function tokens(name: string): string[] {
  return name.replace(/_\d+x\d+x\d+/gi, '_<shape>').split(/(\d+)/);
}

/** Natural order of names ("t2" before "t10"), the text breaking ties. */
function compareNatural(a: string, b: string): number {
  return a.localeCompare(b, 'en', { numeric: true }) || (a < b ? -1 : a > b ? 1 : 0);
}

const list = (ns: number[], max = 3) => (ns.length > max ? `${ns.slice(0, max).join(', ')}, …` : ns.join(', '));

/**
 * The time order of `names` (two or more) and whether the names make it
 * sure. Numbered names compare by their number (t2 before t10, step_9 before
 * step_010).
 */
export function seriesOrder(names: readonly string[]): SeriesOrder {
  const natural = names.map((_, i) => i).sort((a, b) => compareNatural(names[a], names[b]));
  if (names.length < 2) return { order: natural, sure: names.length === 1 };
  const split = names.map(tokens);
  const skeleton = (t: string[]) => t.filter((_, i) => i % 2 === 0).join('\u0000');
  const first = skeleton(split[0]);
  if (split.some((t) => skeleton(t) !== first)) {
    return { order: natural, sure: false, why: 'the names are not numbered alike (no one number that counts the files)' };
  }
  // positions of digit runs whose value differs between files
  const runs = (split[0].length - 1) / 2;
  const varying: number[] = [];
  for (let r = 0; r < runs; r++) {
    const at = 2 * r + 1;
    const values = new Set(split.map((t) => Number(t[at])));
    if (values.size > 1) varying.push(at);
  }
  if (varying.length === 0) {
    return { order: natural, sure: false, why: 'the names carry no number that differs from file to file' };
  }
  const key = (i: number) => varying.map((at) => Number(split[i][at]));
  const byNumbers = names
    .map((_, i) => i)
    .sort((a, b) => {
      const ka = key(a);
      const kb = key(b);
      for (let j = 0; j < ka.length; j++) if (ka[j] !== kb[j]) return ka[j] - kb[j];
      return compareNatural(names[a], names[b]);
    });
  if (varying.length > 1) {
    return { order: byNumbers, sure: false, why: `the names differ in ${varying.length} numbers, not one` };
  }
  const numbers = byNumbers.map((i) => key(i)[0]);
  const twice = numbers.filter((n, j) => j > 0 && numbers[j - 1] === n);
  if (twice.length > 0) {
    return { order: byNumbers, sure: false, why: `more than one file has the number ${list([...new Set(twice)])}`, numbers };
  }
  const step = numbers[1] - numbers[0];
  const uneven = numbers.some((n, j) => j > 0 && n - numbers[j - 1] !== step);
  if (uneven) {
    const missing: number[] = [];
    const seen = new Set(numbers);
    // the smallest step between files, taken as the series' own; the numbers it skips are the gaps
    const least = Math.min(...numbers.slice(1).map((n, j) => n - numbers[j]));
    for (let n = numbers[0]; n <= numbers.at(-1)! && missing.length < 4; n += least) if (!seen.has(n)) missing.push(n);
    return {
      order: byNumbers,
      sure: false,
      why: `the numbers ${numbers[0]}..${numbers.at(-1)} have gaps${missing.length ? ` (no ${list(missing)})` : ''}`,
      numbers,
    };
  }
  return { order: byNumbers, sure: true, numbers };
}

/** How the page names a series: "step_000.raw … step_019.raw (20 time points)". */
export function seriesLabel(ordered: readonly string[]): string {
  if (ordered.length === 1) return ordered[0];
  return `${ordered[0]} … ${ordered.at(-1)} (${ordered.length} time points)`;
}
