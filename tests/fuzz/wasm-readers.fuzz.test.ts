// Seeded fuzzing of the LAS/LAZ and TIFF readers (Wasm modules) through the
// functions the pages and the CLI call (tests/fuzz/targets-wasm.ts). Fails on
// any error that is not the reader's own (naming the file), any failure
// inside a Wasm module (trap, escaped exception: the target reports it as a
// crash), any Wasm heap or JS buffer memory above the limits, any case that
// runs past HANG_MS, and a valid file that no longer opens after the
// mutated ones. FUZZ_CASES=N runs N cases per reader (default 300);
// FUZZ_SEED picks another sequence. Prints the table per reader.
import { describe, expect, test } from 'vitest';
import { loadLasWasm } from '../../src/loaders/las.ts';
import { loadTiffWasm } from '../../src/loaders/tiff.ts';
import { mulberry32 } from '../../src/util/random.ts';
import { wasmFuzzTargets } from './targets-wasm.ts';
import { flipBits, lasField, tiffField, truncate, type Rand } from './wasm-mutate.ts';

const CASES = Number(process.env.FUZZ_CASES ?? 300);
const SEED = Number(process.env.FUZZ_SEED ?? 13);
const HANG_MS = 10_000;
/** One Wasm heap: a 1 GiB page or chunk limit plus the file and the library's buffers. */
const HEAP_LIMIT = 1.25 * 2 ** 30;
/** All JS buffers at once (Wasm heaps included, old ones not yet collected). */
const BUFFERS_LIMIT = 3 * 2 ** 30;

interface Row {
  reader: string;
  cases: number;
  clean: number;
  accepted: number;
  crashes: number;
  hangs: number;
  peakHeapMiB: number;
  peakRssMiB: number;
  slowestMs: number;
}

const rows: Row[] = [];

function mutate(reader: string, seed: Uint8Array, rand: Rand): { bytes: Uint8Array; what: string } {
  const r = rand();
  if (r < 0.2) return truncate(seed, rand);
  if (r < 0.5) return flipBits(seed, rand);
  const field = reader === 'las' ? lasField : tiffField;
  if (r < 0.92) return field(seed, rand);
  // Two at once: a field lie plus a flip.
  const a = field(seed, rand);
  const b = flipBits(a.bytes, rand);
  return { bytes: b.bytes, what: `${a.what}; ${b.what}` };
}

async function heapBytes(reader: string): Promise<number> {
  const m = reader === 'las' ? await loadLasWasm() : await loadTiffWasm();
  return m.HEAPU8.buffer.byteLength;
}

describe.each(wasmFuzzTargets)('fuzz $reader', (target) => {
  test(`${CASES} mutated files: clean rejections only, no trap, no hang, bounded memory`, async () => {
    const seeds = await target.seeds();
    expect(seeds.length).toBeGreaterThan(0);
    // What each valid file gives, to check files after rejected ones.
    const baseline = new Map<string, string>();
    for (const s of seeds) baseline.set(s.name, JSON.stringify(await target.open(s.name, s.bytes)));
    const rand = mulberry32(SEED * 7919 + target.reader.length);
    const row: Row = {
      reader: target.reader,
      cases: 0,
      clean: 0,
      accepted: 0,
      crashes: 0,
      hangs: 0,
      peakHeapMiB: 0,
      peakRssMiB: 0,
      slowestMs: 0,
    };
    const problems: string[] = [];
    let peakBuffers = 0;
    for (let i = 0; i < CASES; i++) {
      const seed = seeds[i % seeds.length];
      const { bytes, what } = mutate(target.reader, seed.bytes, rand);
      const name = `case${i}-${seed.name}`;
      const t0 = performance.now();
      try {
        await target.open(name, bytes);
        row.accepted++;
      } catch (e) {
        if (target.isCleanRejection(e, name)) row.clean++;
        else {
          row.crashes++;
          if (problems.length < 20)
            problems.push(`${name} (${what}): ${(e as Error)?.stack?.split('\n').slice(0, 3).join(' | ') ?? String(e)}`);
        }
      }
      const ms = performance.now() - t0;
      row.slowestMs = Math.max(row.slowestMs, ms);
      if (ms > HANG_MS) {
        row.hangs++;
        problems.push(`${name} (${what}): took ${(ms / 1000).toFixed(1)} s`);
      }
      row.cases++;
      const heap = await heapBytes(target.reader);
      const mem = process.memoryUsage();
      row.peakHeapMiB = Math.max(row.peakHeapMiB, heap / 2 ** 20);
      row.peakRssMiB = Math.max(row.peakRssMiB, mem.rss / 2 ** 20);
      peakBuffers = Math.max(peakBuffers, mem.arrayBuffers);
      if (heap > HEAP_LIMIT) problems.push(`${name} (${what}): Wasm heap grew to ${(heap / 2 ** 20).toFixed(0)} MiB`);
      if (mem.arrayBuffers > BUFFERS_LIMIT) problems.push(`${name} (${what}): ${(mem.arrayBuffers / 2 ** 20).toFixed(0)} MiB of buffers`);
      // A valid file after this one (every 10th case, and always after a crash) opens as before.
      if (i % 10 === 9 || row.crashes > 0) {
        const after = JSON.stringify(await target.open(seed.name, seed.bytes));
        if (after !== baseline.get(seed.name))
          problems.push(`${seed.name} after ${name} (${what}) gives ${after}, not ${baseline.get(seed.name)}`);
      }
    }
    row.peakRssMiB = Math.round(row.peakRssMiB);
    row.peakHeapMiB = Math.round(row.peakHeapMiB);
    row.slowestMs = Math.round(row.slowestMs);
    rows.push(row);
    console.log(
      `fuzz ${target.reader}: cases ${row.cases}, clean rejections ${row.clean}, accepted ${row.accepted}, crashes ${row.crashes}, hangs ${row.hangs}, ` +
        `peak Wasm heap ${row.peakHeapMiB} MiB, peak RSS ${row.peakRssMiB} MiB, peak JS buffers ${Math.round(peakBuffers / 2 ** 20)} MiB, slowest case ${row.slowestMs} ms (seed ${SEED})`,
    );
    expect(problems).toEqual([]);
    expect(row.clean + row.accepted).toBe(CASES);
  });
});
