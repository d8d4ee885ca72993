// The isovalue a newly opened volume starts at. Without a hint (URL, default
// volume), Otsu's threshold over the block midpoints: it splits the blocks
// into two classes (background and object in CT and simulation data alike)
// and so lands on the boundary users usually look for first.

export function otsuThreshold(values: ArrayLike<number>, lo: number, hi: number, bins = 256): number {
  if (!(hi > lo)) return lo;
  const hist = new Float64Array(bins);
  let n = 0;
  for (let i = 0; i < values.length; i++) {
    const v = values[i];
    if (!Number.isFinite(v)) continue;
    const b = Math.min(bins - 1, Math.max(0, Math.floor(((v - lo) / (hi - lo)) * bins)));
    hist[b]++;
    n++;
  }
  if (n === 0) return (lo + hi) / 2;
  let sumAll = 0;
  for (let b = 0; b < bins; b++) sumAll += b * hist[b];
  const between = new Float64Array(bins);
  let w0 = 0,
    sum0 = 0,
    best = -1;
  for (let b = 0; b < bins - 1; b++) {
    w0 += hist[b];
    sum0 += b * hist[b];
    const w1 = n - w0;
    if (w0 === 0 || w1 === 0) continue;
    const m0 = sum0 / w0;
    const m1 = (sumAll - sum0) / w1;
    between[b] = w0 * w1 * (m0 - m1) ** 2;
    best = Math.max(best, between[b]);
  }
  if (best <= 0) return (lo + hi) / 2;
  // Splits in an empty gap between the classes score the same: take the gap's middle.
  let first = -1,
    last = -1;
  for (let b = 0; b < bins - 1; b++) {
    if (between[b] >= best * (1 - 1e-9)) {
      if (first < 0) first = b;
      last = b;
    }
  }
  // The boundary after bin `first` .. after bin `last`.
  return lo + (((first + last) / 2 + 1) / bins) * (hi - lo);
}

/** Midpoints (min + max) / 2 of the blocks that are not constant, from [min, max] pairs. */
export function blockMidpoints(ranges: Float32Array): Float32Array {
  const out = new Float32Array(ranges.length / 2);
  let k = 0;
  for (let i = 0; i < ranges.length; i += 2) {
    // Constant blocks hold no surface; they would only weigh the background.
    if (ranges[i + 1] > ranges[i]) out[k++] = (ranges[i] + ranges[i + 1]) / 2;
  }
  return out.subarray(0, k);
}

export function chooseIsovalue(ranges: Float32Array, valueRange: [number, number]): number {
  const [lo, hi] = valueRange;
  const mids = blockMidpoints(ranges);
  const t = otsuThreshold(mids.length > 0 ? mids : ranges, lo, hi);
  // Keep clear of the extremes, where nothing is drawn.
  const margin = (hi - lo) * 0.01;
  return Math.min(hi - margin, Math.max(lo + margin, t));
}
