// `npm run bench:rate`: the rate chosen from the data (src/zfp/rate-choice.ts)
// per source type: the rate, the compressed size, the time spent choosing
// against the whole load (choose + compress with the error measured +
// pipeline setup + first surface), and the triangles and area against
// vtkMarchingCubes on the raw data, at the chosen rate and at the old default 8.
// Volumes: the tests' CT-like int16 scan and uint16 blobs
// (tests/fixtures/rate-volumes.py), the shared uint8 and float32 volumes.
// Times: median of the repeats after a discarded first (pipelines compiled).
//
//   node benchmarks/run.mjs benchmarks/rate-choice.ts [--repeats N] [--json FILE]
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { describeAdapter } from '../src/gpu/device.ts';
import { requestNodeGpu } from '../src/gpu/node-gpu.ts';
import { Isosurface } from '../src/isosurface/isosurface.ts';
import { meshMetrics } from '../src/mc/mesh-metrics.ts';
import { meshPositions } from '../src/isosurface/vertex-format.ts';
import { soupOf } from '../src/mc/ply.ts';
import { openVolumeBytes, type OpenedVolume } from '../src/volume/open-volume.ts';
import { printTable, summarize, writeJson } from './lib/report.ts';

const root = fileURLToPath(new URL('..', import.meta.url));
const shared = join(root, '..', 'shared', 'data', 'volumes');
const python = join(root, '.venv', 'bin', 'python');

const args = process.argv.slice(2);
let repeats = 4; // 3 measured after the discarded first
let jsonOut = join(root, 'benchmarks', 'results', 'rate-choice-swiftshader.json');
for (let i = 0; i < args.length; i++) {
  if (args[i] === '--repeats') repeats = Number(args[++i]) + 1;
  else if (args[i] === '--json') jsonOut = args[++i];
}

const work = mkdtempSync(join(tmpdir(), 'bench-rate-'));
execFileSync(python, [join(root, 'tests/fixtures/rate-volumes.py'), work]);

const volumes = [
  { file: 'ct_128x128x256_int16.raw', path: join(work, 'ct_128x128x256_int16.raw'), isovalues: [-500.3, 47.3, 300.3] },
  { file: 'blobs_160x160x128_uint16.raw', path: join(work, 'blobs_160x160x128_uint16.raw'), isovalues: [1000.5, 4000.5] },
  { file: 'neghip_66x66x66_uint8.raw', path: join(shared, 'neghip_66x66x66_uint8.raw'), isovalues: [50.5, 120.5] },
  { file: 'ironProt_68x68x68_uint8.raw', path: join(shared, 'ironProt_68x68x68_uint8.raw'), isovalues: [37.37, 128.37] },
  { file: 'hydrogen_atom_128x128x128_float32.raw', path: join(shared, 'hydrogen_atom_128x128x128_float32.raw'), isovalues: [9.37, 37.37] },
  { file: 'fuel_64x64x64_float32.raw', path: join(shared, 'fuel_64x64x64_float32.raw'), isovalues: [10.37, 80.37] },
];

const gpu = await requestNodeGpu({ label: 'bench.rate' });

async function surfaces(opened: OpenedVolume, isovalues: number[]): Promise<{ triangles: number; area: number; ms: number }[]> {
  const iso = await Isosurface.create(gpu, opened.stream, { memoryBudgetBytes: 512 * 2 ** 20 });
  try {
    const out = [];
    for (const v of isovalues) {
      const t0 = performance.now();
      const stats = await iso.compute(v);
      const ms = performance.now() - t0;
      const mesh = await iso.readMesh();
      const soup = soupOf(meshPositions(mesh), mesh.indices);
      out.push({ triangles: stats.triangles, area: meshMetrics(soup).area, ms });
    }
    return out;
  } finally {
    iso.destroy();
  }
}

const rows: (string | number)[][] = [];
const records = [];
try {
  for (const v of volumes) {
    const bytes = new Uint8Array(readFileSync(v.path));
    const dims = v.file
      .match(/_(\d+)x(\d+)x(\d+)_/)!
      .slice(1)
      .map(Number);
    const dtype = v.file.match(/_([a-z0-9]+)\.raw$/)![1];
    const vtk = JSON.parse(
      execFileSync(python, [join(root, 'tests/fixtures/vtk-surface.py'), v.path, dtype, ...dims.map(String), v.isovalues.join(',')], {
        encoding: 'utf8',
      }),
    ) as [number, number][];
    const chooseMs: number[] = [];
    const openMs: number[] = [];
    const loadMs: number[] = [];
    let chosen: OpenedVolume | undefined;
    let chosenSurfaces: { triangles: number; area: number; ms: number }[] = [];
    for (let r = 0; r < repeats; r++) {
      chosen?.stream.destroy();
      const t0 = performance.now();
      chosen = await openVolumeBytes(gpu.device, bytes, v.file);
      const t1 = performance.now();
      // the load ends with the first surface on screen
      const iso = await Isosurface.create(gpu, chosen.stream, { memoryBudgetBytes: 512 * 2 ** 20 });
      await iso.compute(v.isovalues[0]);
      iso.destroy();
      const t2 = performance.now();
      if (r === 0) continue;
      chooseMs.push(chosen.rateChoice!.ms);
      openMs.push(t1 - t0);
      loadMs.push(t2 - t0);
    }
    chosenSurfaces = await surfaces(chosen!, v.isovalues);
    const old = await openVolumeBytes(gpu.device, bytes, v.file, { rate: 8 });
    const oldSurfaces = await surfaces(old, v.isovalues);
    const c = chosen!.rateChoice!;
    const choose = summarize(chooseMs);
    const load = summarize(loadMs);
    const deviation = (s: { triangles: number; area: number }[], i: number) => ({
      triangles: s[i].triangles / vtk[i][0] - 1,
      area: s[i].area / vtk[i][1] - 1,
    });
    const worst = (s: { triangles: number; area: number }[]) => Math.max(...v.isovalues.map((_, i) => Math.abs(deviation(s, i).triangles)));
    rows.push([
      v.file.replace(/_\d+x\d+x\d+_/, ' '),
      chosen!.rate,
      chosen!.compressedBytes / 2 ** 20,
      bytes.byteLength / chosen!.compressedBytes,
      c.sample.rms,
      c.stream!.rms,
      choose.median,
      load.median,
      (100 * choose.median) / load.median,
      100 * worst(chosenSurfaces),
      100 * worst(oldSurfaces),
    ]);
    records.push({
      file: v.file,
      dtype,
      dims,
      sourceBytes: bytes.byteLength,
      rate: chosen!.rate,
      compressedBytes: chosen!.compressedBytes,
      rateAt8Bytes: old.compressedBytes,
      rateChoice: { how: c.how, bound: c.bound, sample: c.sample, stream: c.stream, trials: c.trials, sampleBlocks: c.sampleBlocks },
      chooseMs: choose,
      openMs: summarize(openMs),
      loadMs: load,
      isovalues: v.isovalues.map((iso, i) => ({
        iso,
        vtk: { triangles: vtk[i][0], area: vtk[i][1] },
        chosen: { ...chosenSurfaces[i], ...deviation(chosenSurfaces, i) },
        rate8: { ...oldSurfaces[i], ...deviation(oldSurfaces, i) },
      })),
    });
    chosen!.stream.destroy();
    old.stream.destroy();
  }
} finally {
  rmSync(work, { recursive: true, force: true });
}

printTable(
  `The rate chosen from the data (${describeAdapter(gpu.adapter)}; median of ${repeats - 1} after a discarded first)`,
  [
    'volume',
    'rate',
    'MiB',
    'ratio',
    'sample RMS',
    'stream RMS',
    'choose ms',
    'load ms',
    'choose %',
    'worst |tri-VTK| % chosen',
    'at rate 8',
  ],
  rows,
);
writeJson(jsonOut, { adapter: describeAdapter(gpu.adapter), repeats: repeats - 1, volumes: records });
gpu.device.destroy();
