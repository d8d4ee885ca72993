// Benchmark inputs: xorshift32 words, the same sequence for a seed on every run.

/** `n` xorshift32 words from `seed` (each % `modulo` when given). */
export function xorshiftWords(n: number, seed: number, modulo = 0): Uint32Array<ArrayBuffer> {
  let s = seed >>> 0 || 1;
  const a = new Uint32Array(n);
  for (let i = 0; i < n; i++) {
    s ^= s << 13;
    s ^= s >>> 17;
    s ^= s << 5;
    a[i] = modulo ? (s >>> 0) % modulo : s >>> 0;
  }
  return a;
}
