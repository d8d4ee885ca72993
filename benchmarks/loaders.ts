// `npm run bench:loaders`: load time of the Wasm loaders next to native and
// JavaScript peers, in the same run, median of N after a discarded first.
//
// LAS/LAZ (points/s): our LASzip Wasm module (positions, RGB, intensity and
// class, as the LIDAR page reads them) vs the same C API and LASzip sources
// compiled natively with gcc -O3, vs laspy with the native LASzip backend
// (PyPI `laszip`) and with lazrs (Rust), vs laz-perf from npm (its Wasm
// build; LAZ only, raw point records).
// TIFF (MB/s of decoded samples): our libtiff Wasm module vs the same C API
// natively, vs tifffile (+imagecodecs), vs geotiff from npm (pure JS).
//
//   node benchmarks/run.mjs benchmarks/loaders.ts [--repeats N] [--json FILE]
// Wasm here runs in Node's V8, the engine of Chrome; the browser adds little.
import { execFileSync, spawnSync } from 'node:child_process';
import { existsSync, readFileSync } from 'node:fs';
import { basename, join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { createLazPerf } from 'laz-perf';
import { fromArrayBuffer } from 'geotiff';
import { LasReader } from '../src/loaders/las.ts';
import { loadTiffStack } from '../src/loaders/tiff.ts';
import { printTable, summarize, writeJson, type Stats } from './lib/report.ts';

const root = fileURLToPath(new URL('..', import.meta.url));
const shared = join(root, '..', 'shared', 'data');
const nativeDir = join(root, 'wasm', '.build', 'native');

const args = process.argv.slice(2);
let repeats = 9; // 8 measured after the discarded first
let jsonOut = join(root, 'benchmarks', 'results', 'loaders.json');
for (let i = 0; i < args.length; i++) {
  if (args[i] === '--repeats') repeats = Number(args[++i]) + 1;
  else if (args[i] === '--json') jsonOut = args[++i];
}

const LAS_FILES = ['las/lazperf_autzen_trim.laz', 'las/lazperf_autzen_trim.las'];
const TIFF_FILES = ['tiff/morpholibj_bat-cochlea-volume.tif', 'tiff/imagejs_stack.tif', 'tiff/imagejs_image-lzw.tif'];

async function timeAsync(fn: () => Promise<unknown> | unknown): Promise<Stats> {
  const ms: number[] = [];
  for (let i = 0; i < repeats; i++) {
    const t0 = performance.now();
    await fn();
    ms.push(performance.now() - t0);
  }
  return summarize(ms);
}

function statsFromMs(ms: number[]): Stats {
  return summarize(ms);
}

/** The native baseline (same C API, gcc): built on demand by wasm/build.mjs --native-only. */
function ensureNative(): string | undefined {
  if (existsSync(join(nativeDir, 'las_bench')) && existsSync(join(nativeDir, 'tiff_bench'))) return undefined;
  console.error('building the native baseline (node wasm/build.mjs --native-only)...');
  const r = spawnSync(process.execPath, [join(root, 'wasm', 'build.mjs'), '--native-only'], { stdio: 'inherit' });
  return r.status === 0 ? undefined : 'native build failed (needs gcc, cmake, dpkg-dev and the registries)';
}

function native(tool: 'las_bench' | 'tiff_bench', file: string): Stats {
  const out = execFileSync(join(nativeDir, tool), [file, String(repeats)], { encoding: 'utf8', maxBuffer: 1 << 24 });
  return statsFromMs(JSON.parse(out).ms);
}

function python(): string {
  return join(root, '.venv', 'bin', 'python');
}

const PY_LAS = `
import sys, json, time, laspy
path, repeats, backend = sys.argv[1], int(sys.argv[2]), sys.argv[3]
be = {'laszip': laspy.LazBackend.Laszip, 'lazrs': laspy.LazBackend.Lazrs}[backend]
if not be.is_available(): print(json.dumps({'error': backend + ' backend not installed'})); sys.exit()
data = open(path, 'rb').read()
import io
ms = []
for _ in range(repeats):
    t = time.perf_counter()
    las = laspy.read(io.BytesIO(data), laz_backend=be)
    # The same fields the page takes: scaled xyz, colour, intensity, class.
    x, y, z = las.x, las.y, las.z
    _ = (x.array, las.intensity, las.classification)
    if 'red' in las.point_format.dimension_names: _ = (las.red, las.green, las.blue)
    ms.append((time.perf_counter() - t) * 1e3)
print(json.dumps({'ms': ms}))
`;

const PY_TIFF = `
import sys, json, time, tifffile, io
path, repeats = sys.argv[1], int(sys.argv[2])
data = open(path, 'rb').read()
ms = []
for _ in range(repeats):
    t = time.perf_counter()
    a = tifffile.imread(io.BytesIO(data))
    ms.append((time.perf_counter() - t) * 1e3)
print(json.dumps({'ms': ms}))
`;

function py(code: string, argv: string[]): Stats | string {
  if (!existsSync(python())) return '.venv missing (run npm test once)';
  try {
    const out = JSON.parse(execFileSync(python(), ['-c', code, ...argv], { encoding: 'utf8', maxBuffer: 1 << 24 }));
    return out.error ? String(out.error) : statsFromMs(out.ms);
  } catch (e) {
    return `python failed: ${(e as Error).message.split('\n')[0]}`;
  }
}

async function ours(bytes: Uint8Array, name: string): Promise<number> {
  const r = await LasReader.open(bytes, name);
  try {
    const fields = { positions: true, rgb: r.header.hasRGB, intensity: true, classification: true };
    while (r.read(1 << 18, fields)) {
      // chunks go to the GPU in the page; here they are dropped
    }
    return r.header.pointCount;
  } finally {
    r.close();
  }
}

async function lazPerf(bytes: Uint8Array): Promise<number> {
  const m = await lazPerfModule;
  const file = m._malloc(bytes.byteLength);
  m.HEAPU8.set(bytes, file);
  const laszip = new m.LASZip();
  try {
    laszip.open(file, bytes.byteLength);
    const n = laszip.getCount();
    const point = m._malloc(laszip.getPointLength());
    for (let i = 0; i < n; i++) laszip.getPoint(point);
    m._free(point);
    return n;
  } finally {
    laszip.delete();
    m._free(file);
  }
}
const lazPerfModule = createLazPerf();

async function geotiff(bytes: Uint8Array): Promise<void> {
  const ab = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength) as ArrayBuffer;
  // geotiff's LZW decoder warns for every strip that lacks an end code (the file is valid).
  const { log, warn } = console;
  console.log = console.warn = () => undefined;
  try {
    const tiff = await fromArrayBuffer(ab);
    const count = await tiff.getImageCount();
    for (let i = 0; i < count; i++) {
      const image = await tiff.getImage(i);
      await image.readRasters({ interleave: true });
    }
  } finally {
    console.log = log;
    console.warn = warn;
  }
}

async function main(): Promise<void> {
  const nativeProblem = ensureNative();
  const lasRows: (string | number)[][] = [];
  const tiffRows: (string | number)[][] = [];
  const results: { las: Record<string, unknown>[]; tiff: Record<string, unknown>[] } = { las: [], tiff: [] };

  for (const rel of LAS_FILES) {
    const path = join(shared, rel);
    const bytes = new Uint8Array(readFileSync(path));
    const name = basename(path);
    const points = await ours(bytes, name);
    const entries: { reader: string; stats: Stats | string }[] = [];
    entries.push({ reader: 'ours: LASzip → Wasm (Node V8)', stats: await timeAsync(() => ours(bytes, name)) });
    entries.push({ reader: 'native: same C API, gcc -O3', stats: nativeProblem ?? native('las_bench', path) });
    if (name.endsWith('.laz')) {
      entries.push({ reader: 'laspy + LASzip (native)', stats: py(PY_LAS, [path, String(repeats), 'laszip']) });
      entries.push({ reader: 'laspy + lazrs (Rust)', stats: py(PY_LAS, [path, String(repeats), 'lazrs']) });
    } else {
      // Uncompressed LAS needs no decoder: laspy maps the records with numpy.
      entries.push({ reader: 'laspy (numpy)', stats: py(PY_LAS, [path, String(repeats), 'laszip']) });
    }
    let lp: Stats | string;
    try {
      await lazPerf(bytes);
      lp = await timeAsync(() => lazPerf(bytes));
    } catch (e) {
      lp = `laz-perf cannot read it (${String((e as Error).message ?? e).slice(0, 60)})`;
    }
    entries.push({ reader: 'laz-perf (npm, Wasm)', stats: lp });
    const oursMs = (entries[0].stats as Stats).median;
    for (const e of entries) {
      if (typeof e.stats === 'string') {
        lasRows.push([name, e.reader, 'n/a', 'n/a', 'n/a', e.stats]);
        results.las.push({ file: name, reader: e.reader, note: e.stats });
        continue;
      }
      const ms = e.stats.median;
      lasRows.push([name, e.reader, ms, points / ms / 1e3, oursMs / ms, '']);
      results.las.push({
        file: name,
        points,
        reader: e.reader,
        medianMs: ms,
        mPointsPerS: points / ms / 1e3,
        oursOverThis: oursMs / ms,
        samples: e.stats.samples,
      });
    }
  }
  printTable(
    `LAS/LAZ load (median of ${repeats - 1} after a discarded first; ratio = our time / theirs, > 1 means we are slower)`,
    ['file', 'reader', 'ms', 'M points/s', 'ours/this', 'note'],
    lasRows,
  );

  for (const rel of TIFF_FILES) {
    const path = join(shared, rel);
    const bytes = new Uint8Array(readFileSync(path));
    const name = basename(path);
    const v = await loadTiffStack({ name, bytes });
    const mb = v.data.byteLength / 1e6;
    const entries: { reader: string; stats: Stats | string }[] = [];
    entries.push({ reader: 'ours: libtiff → Wasm (Node V8)', stats: await timeAsync(() => loadTiffStack({ name, bytes })) });
    entries.push({ reader: 'native: same C API, gcc -O3', stats: nativeProblem ?? native('tiff_bench', path) });
    entries.push({ reader: 'tifffile + imagecodecs', stats: py(PY_TIFF, [path, String(repeats)]) });
    let gt: Stats | string;
    try {
      await geotiff(bytes);
      gt = await timeAsync(() => geotiff(bytes));
    } catch (e) {
      gt = `geotiff cannot read it (${String((e as Error).message ?? e).slice(0, 60)})`;
    }
    entries.push({ reader: 'geotiff (npm, JS)', stats: gt });
    const oursMs = (entries[0].stats as Stats).median;
    for (const e of entries) {
      if (typeof e.stats === 'string') {
        tiffRows.push([name, e.reader, 'n/a', 'n/a', 'n/a', e.stats]);
        results.tiff.push({ file: name, reader: e.reader, note: e.stats });
        continue;
      }
      const ms = e.stats.median;
      tiffRows.push([name, e.reader, ms, mb / (ms / 1e3), oursMs / ms, '']);
      results.tiff.push({
        file: name,
        decodedMB: mb,
        pages: v.pages.length,
        reader: e.reader,
        medianMs: ms,
        MBperS: mb / (ms / 1e3),
        oursOverThis: oursMs / ms,
        samples: e.stats.samples,
      });
    }
  }
  printTable(
    `TIFF load (median of ${repeats - 1} after a discarded first; MB/s of decoded samples; ratio = our time / theirs)`,
    ['file', 'reader', 'ms', 'MB/s', 'ours/this', 'note'],
    tiffRows,
  );
  writeJson(jsonOut, { date: new Date().toISOString(), node: process.version, repeats: repeats - 1, ...results });
}

await main();
