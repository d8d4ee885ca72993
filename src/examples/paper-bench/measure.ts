// The CPU-side measurements of the paper's comparison benchmarks, shared by
// the benchmark page (paper-bench.html, in the browser) and `npm run
// bench:paper` (in Node), so "JS in Chromium" and "JS in Node" time the very
// same code: serial marching cubes in TypeScript and in WebAssembly (the C++
// twin, benchmarks/serial-mc/), zfp's C decoder in WebAssembly, and the
// isovalue range of interest of a volume.
import { WasmSerialMc } from '../../mc/serial-mc-wasm.ts';
import { ZfpWasmStream } from '../../loaders/zfp-wasm.ts';
import { marchingCubes, type Dims3 } from '../../mc/serial-mc.ts';

export type SerialMethod = 'js' | 'wasm';

/** One surface per isovalue, in order: ms and triangles of each. */
export interface SerialTimes {
  ms: number[];
  triangles: number[];
}

/**
 * Serial marching cubes of `values` at each isovalue, once each, with each
 * method; the methods take turns per isovalue, so background load hits them
 * alike. TS times include allocating the soup; Wasm times include its malloc
 * of the soup (the volume is copied into the Wasm heap once, before timing).
 * Throws if the methods disagree on a triangle count.
 */
export async function timeSerialMc(
  values: Float32Array,
  dims: Dims3,
  isovalues: number[],
  methods: SerialMethod[],
  onProgress?: (done: number, total: number) => void,
): Promise<Partial<Record<SerialMethod, SerialTimes>>> {
  const out: Partial<Record<SerialMethod, SerialTimes>> = {};
  for (const m of methods) out[m] = { ms: [], triangles: [] };
  const wasm = methods.includes('wasm') ? await WasmSerialMc.create() : undefined;
  try {
    wasm?.setVolume(values, dims);
    for (let q = 0; q < isovalues.length; q++) {
      const iso = isovalues[q];
      for (const m of methods) {
        const t0 = performance.now();
        const triangles = m === 'js' ? marchingCubes(values, dims, iso).triangleCount : wasm!.run(iso, { copyOut: false }).triangleCount;
        const ms = performance.now() - t0;
        out[m]!.ms.push(ms);
        out[m]!.triangles.push(triangles);
      }
      const counts = methods.map((m) => out[m]!.triangles[q]);
      if (counts.some((n) => n !== counts[0]))
        throw new Error(`serial MC methods disagree at iso ${iso}: ${methods.map((m, i) => `${m} ${counts[i]}`).join(', ')}`);
      onProgress?.(q + 1, isovalues.length);
      // Let the page repaint and the driver's protocol breathe between surfaces.
      if (q % 8 === 7) await new Promise((r) => setTimeout(r, 0));
    }
  } finally {
    wasm?.dispose();
  }
  return out;
}

/** zfp's C decoder in Wasm on a fixed-rate stream with header: ms per whole-volume decode. */
export async function timeZfpWasm(
  bytes: Uint8Array,
  runs: number,
  name = 'stream',
): Promise<{ ms: number[]; dims: Dims3; floatBytes: number; sample: number[] }> {
  const s = await ZfpWasmStream.load(bytes, name);
  try {
    const ms: number[] = [];
    for (let r = 0; r < runs; r++) {
      const t0 = performance.now();
      s.decode();
      ms.push(performance.now() - t0);
    }
    const out = s.output();
    // A few values, so the runner can check this decode against the others.
    const sample = [0, 1, out.length >> 1, out.length - 1].filter((i) => i < out.length).map((i) => out[i]);
    return { ms, dims: s.info.dims, floatBytes: s.count * 4, sample };
  } finally {
    s.free();
  }
}

/** Mean of all but the first sample (the first run is a warm-up, as in the paper). */
export function meanAfterFirst(xs: number[]): number {
  const kept = xs.length > 1 ? xs.slice(1) : xs;
  return kept.reduce((s, x) => s + x, 0) / Math.max(1, kept.length);
}

/**
 * Isovalue range of interest from the data, for volumes without a chosen one
 * (the paper: "a range covering surfaces typically of interest to users,
 * excluding noise and values so high as to produce few output triangles").
 * Over the 4x4x4 blocks whose value range spans more than 5% of the volume's
 * (structure, not noise or flat background), the 10th to 90th percentile of
 * their maxima. On the shared volumes this gives fuel [18.5, 209],
 * hydrogen [19.4, 62.5], bonsai [20.1, 183], close to the spans of their
 * reference isovalues (mc_spec.json: 10.37-200.37, 2.37-60.37, 20.37-200.37).
 */
export function interestingRange(values: Float32Array, dims: Dims3): [number, number] {
  const [nx, ny, nz] = dims;
  let lo = Infinity;
  let hi = -Infinity;
  for (const v of values) {
    if (v < lo) lo = v;
    if (v > hi) hi = v;
  }
  if (!(hi > lo)) return [lo, hi];
  const maxima: number[] = [];
  const threshold = 0.05 * (hi - lo);
  for (let bz = 0; bz < nz; bz += 4)
    for (let by = 0; by < ny; by += 4)
      for (let bx = 0; bx < nx; bx += 4) {
        let bmin = Infinity;
        let bmax = -Infinity;
        for (let z = bz; z < Math.min(bz + 4, nz); z++)
          for (let y = by; y < Math.min(by + 4, ny); y++)
            for (let x = bx; x < Math.min(bx + 4, nx); x++) {
              const v = values[x + nx * (y + ny * z)];
              if (v < bmin) bmin = v;
              if (v > bmax) bmax = v;
            }
        if (bmax - bmin > threshold) maxima.push(bmax);
      }
  if (maxima.length < 2) return [lo + 0.1 * (hi - lo), hi - 0.1 * (hi - lo)];
  maxima.sort((a, b) => a - b);
  const pct = (p: number) => maxima[Math.min(maxima.length - 1, Math.floor(p * (maxima.length - 1)))];
  const a = pct(0.1);
  const b = pct(0.9);
  return b > a ? [a, b] : [lo + 0.1 * (hi - lo), hi - 0.1 * (hi - lo)];
}
