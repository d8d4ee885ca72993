// Fuzz targets for the two readers built on Wasm modules: LAS/LAZ (LASzip)
// and TIFF (libtiff). open() calls what the LIDAR page and `cli las` call
// (LasReader.open, then read() in chunks with the page's and the CLI's
// fields), and what the neuron page and `cli tiff` call (TiffReader.open on
// every file, loadTiffStack). A failure inside a module is turned into the
// reader's error for the user (and the module replaced); here it is reported
// as a crash, since a file must never make the module fail.
import { readdirSync, readFileSync } from 'node:fs';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { LasError, LasReader } from '../../src/loaders/las.ts';
import { loadTiffStack, TiffError, TiffReader } from '../../src/loaders/tiff.ts';
import { wasmFailures } from '../../src/loaders/wasm-module.ts';
import type { FuzzSeed, FuzzTarget } from './target.ts';

const sharedData = fileURLToPath(new URL('../../../shared/data/', import.meta.url));

function seedsFrom(dir: string, pattern: RegExp): FuzzSeed[] {
  return readdirSync(join(sharedData, dir))
    .filter((f) => pattern.test(f))
    .sort()
    .map((name) => {
      const b = readFileSync(join(sharedData, dir, name));
      return { name, bytes: new Uint8Array(b.buffer, b.byteOffset, b.byteLength) };
    });
}

/** Runs `open`, and reports a module failure during it as a crash (not the reader's clean error). */
async function watchingModules<T>(open: () => Promise<T>): Promise<T> {
  const before = wasmFailures.length;
  let outcome: { ok: true; value: T } | { ok: false; error: unknown };
  try {
    outcome = { ok: true, value: await open() };
  } catch (error) {
    outcome = { ok: false, error };
  }
  if (wasmFailures.length > before) throw new Error(`Wasm module failure: ${wasmFailures.slice(before).join('; ')}`);
  if (!outcome.ok) throw outcome.error;
  return outcome.value;
}

/** Page (2^18 points, positions/RGB/intensity/class) and CLI (xyz, records) fields in one pass. */
async function openLas(name: string, bytes: Uint8Array): Promise<unknown> {
  const reader = await LasReader.open(bytes, name);
  try {
    const h = reader.header;
    let points = 0;
    for (;;) {
      const c = reader.read(1 << 18, { positions: true, rgb: h.hasRGB, intensity: true, classification: true, xyz: true, records: true });
      if (!c) break;
      points += c.count;
    }
    return { points, format: h.pointFormat, compressed: h.compressed, warnings: reader.warnings.length };
  } finally {
    reader.close();
  }
}

async function openTiff(name: string, bytes: Uint8Array): Promise<unknown> {
  // As `cli tiff` does: count every directory first, then load the stack.
  const r = await TiffReader.open(bytes, name);
  const ifds = r.pageCount;
  r.close();
  const v = await loadTiffStack({ name, bytes });
  return { ifds, dims: v.dims, dtype: v.dtype, samples: v.data.length };
}

export const wasmFuzzTargets: FuzzTarget[] = [
  {
    reader: 'las',
    seeds: async () => seedsFrom('las', /\.(las|laz)$/i),
    open: (name, bytes) => watchingModules(() => openLas(name, bytes)),
    isCleanRejection: (e, name) => e instanceof LasError && e.fileName === name && e.message.includes(name),
  },
  {
    reader: 'tiff',
    seeds: async () => seedsFrom('tiff', /\.tiff?$/i),
    open: (name, bytes) => watchingModules(() => openTiff(name, bytes)),
    isCleanRejection: (e, name) => e instanceof TiffError && e.fileName === name && e.message.includes(name),
  },
];
