// Serial marching cubes: TypeScript vs WebAssembly vs native C++ (paper section 3.3.3),
// one surface at a time, on the shared volumes.
//   node benchmarks/run.mjs benchmarks/serial-mc/bench.ts [--repeat N] [--random N] [--volumes fuel,bonsai] [--json FILE]
// Isovalues: the 5 of mc.json per volume, or --random N drawn uniformly between the
// lowest and highest of those (seeded). Each surface runs `repeat` times; the first
// run is discarded and the median kept. Native times are taken inside the binary
// (no process start or file read); Wasm times include its malloc of the soup but no
// copy out of the heap; TS times include allocating the output arrays.
import { execFileSync } from 'node:child_process';
import { mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { marchingCubes } from '../../src/mc/serial-mc.ts';
import { loadMcReference, loadMcVolume, rng, ROOT } from '../../tests/unit/mc/reference.ts';
import { printTable, summarize, writeJson, type Cell } from '../lib/report.ts';
import { WasmSerialMc } from '../../src/mc/serial-mc-wasm.ts';

function arg(name: string): string | undefined {
  const i = process.argv.indexOf(`--${name}`);
  return i >= 0 ? process.argv[i + 1] : undefined;
}

const repeat = Number(arg('repeat') ?? 5);
const randomCount = arg('random') ? Number(arg('random')) : 0;
const only = arg('volumes')?.split(',');
const DEFAULT = ['fuel_64x64x64_float32.raw', 'hydrogen_atom_128x128x128_float32.raw', 'bonsai_256x256x256_float32.rate4.zfp'];

const volumes = loadMcReference().volumes.filter((v) =>
  only ? only.some((o) => v.file.includes(o)) : DEFAULT.some((d) => v.file.endsWith(d)),
);
const binary = execFileSync(process.execPath, [join(ROOT, 'benchmarks', 'serial-mc', 'build.mjs'), 'native', '--if-stale'], {
  encoding: 'utf8',
})
  .trim()
  .split('\n')
  .pop()!;
const wasm = await WasmSerialMc.create();
const dir = mkdtempSync(join(tmpdir(), 'zfpiso-serial-mc-'));
const rows: Cell[][] = [];
const results: unknown[] = [];
try {
  for (const v of volumes) {
    const values = loadMcVolume(v, dir);
    const dims = v.dims_xyz;
    const given = v.isosurfaces.map((s) => s.iso);
    const r = rng(42);
    const lo = Math.min(...given);
    const hi = Math.max(...given);
    const isos = randomCount > 0 ? Array.from({ length: randomCount }, () => Math.fround(lo + r() * (hi - lo))) : given;
    const raw = join(dir, 'volume.f32');
    writeFileSync(raw, values);
    const native = JSON.parse(
      execFileSync(binary, [raw, ...dims.map(String), isos.map(String).join(','), '--repeat', String(repeat)], {
        encoding: 'utf8',
        maxBuffer: 1 << 26,
      }),
    ) as { results: { triangles: number; ms: number[] }[] };
    wasm.setVolume(values, dims);
    const perIso = isos.map((iso, q) => {
      let triangles = 0;
      const ts = summarize(
        Array.from({ length: repeat }, () => {
          const t0 = performance.now();
          triangles = marchingCubes(values, dims, iso).triangleCount;
          return performance.now() - t0;
        }),
      );
      const w = summarize(
        Array.from({ length: repeat }, () => {
          const t0 = performance.now();
          const n = wasm.run(iso, { copyOut: false }).triangleCount;
          const ms = performance.now() - t0;
          if (n !== triangles) throw new Error(`Wasm gave ${n} triangles, TS ${triangles} (iso ${iso})`);
          return ms;
        }),
      );
      const nat = native.results[q];
      if (nat.triangles !== triangles) throw new Error(`native gave ${nat.triangles} triangles, TS ${triangles} (iso ${iso})`);
      return { iso, triangles, tsMs: ts.median, wasmMs: w.median, nativeMs: summarize(nat.ms).median };
    });
    const mean = (k: 'tsMs' | 'wasmMs' | 'nativeMs') => perIso.reduce((s, p) => s + p[k], 0) / perIso.length;
    const name = v.file.replace('volumes/', '');
    const tri = perIso.reduce((s, p) => s + p.triangles, 0) / perIso.length;
    rows.push([
      name,
      isos.length,
      Math.round(tri),
      mean('nativeMs'),
      mean('wasmMs'),
      mean('tsMs'),
      mean('wasmMs') / mean('nativeMs'),
      mean('tsMs') / mean('nativeMs'),
    ]);
    results.push({ volume: v.file, dims, repeat, perIso });
  }
} finally {
  wasm.dispose();
  rmSync(dir, { recursive: true, force: true });
}
printTable(
  `Serial marching cubes, mean over isovalues of the median ms per surface (repeat ${repeat}, first discarded)`,
  ['volume', 'isos', 'triangles', 'native ms', 'wasm ms', 'ts ms', 'wasm/native', 'ts/native'],
  rows,
);
const json = arg('json');
if (json) writeJson(json, { node: process.version, repeat, results });
