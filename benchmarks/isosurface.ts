// `npm run bench:isosurface`: the GPU isosurface pipeline (src/isosurface/)
// against VTK's vtkFlyingEdges3D on the same decoded volumes and isovalues, in
// the same run, and how its time grows with the volume's size.
//
// 1. For the shared bonsai (256^3, rate 4) and hydrogen atom (128^3, rate 8)
//    files: the paper's benchmark (random, sweep up, sweep down; N isovalues
//    each, seeded, first discarded, cold cache per mode) through the shared
//    harness, then vtkFlyingEdges3D (tools/isosurface/vtk_flying_edges.py,
//    median of repeats) on our GPU decode of the same stream at every
//    isovalue used: mean ms per isovalue, hit rates, ratio ours / VTK.
// 2. Embedding: a sphere field in a 64^3 volume, and the same 64^3 values
//    placed block-aligned in a 512^3 volume that is constant elsewhere, both
//    compressed at rate 8 on the GPU: the same surfaces (asserted), warm-cache
//    GPU time per stage in both, and VTK on both.
//
//   node benchmarks/run.mjs benchmarks/isosurface.ts [--count 100] [--repeats 3] [--volumes bonsai,hydrogen] [--no-embed]
// Writes benchmarks/results/isosurface-<adapter>.json.
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { runBenchmark, type BenchRecord } from '../src/bench/harness.ts';
import { BENCH_MODES } from '../src/bench/sequences.ts';
import { describeAdapter } from '../src/gpu/device.ts';
import { requestNodeGpu } from '../src/gpu/node-gpu.ts';
import { Isosurface } from '../src/isosurface/isosurface.ts';
import type { IsosurfaceStats } from '../src/isosurface/types.ts';
import { compressOnGpu } from '../src/volume/open-volume.ts';
import type { Dims } from '../src/core/naming.ts';
import { ZfpDecoder } from '../src/zfp/decoder.ts';
import { loadZfpStream, type ZfpGpuStream } from '../src/zfp/gpu-stream.ts';
import { printTable, writeJson } from './lib/report.ts';

const root = fileURLToPath(new URL('..', import.meta.url));
const shared = join(root, '..', 'shared', 'data', 'volumes');

function arg(name: string, fallback: string): string {
  const i = process.argv.indexOf(`--${name}`);
  return i >= 0 && process.argv[i + 1] ? process.argv[i + 1] : fallback;
}
const count = Number(arg('count', '100'));
const repeats = Number(arg('repeats', '3'));
const volumeNames = arg('volumes', 'bonsai,hydrogen').split(',');
const embed = !process.argv.includes('--no-embed');

/** Isovalue ranges of interest (as the paper: no noise, no near-empty surfaces). */
const VOLUMES: Record<string, { file: string; range: [number, number] }> = {
  bonsai: { file: 'bonsai_256x256x256_float32.rate4.zfp', range: [30, 200] },
  hydrogen: { file: 'hydrogen_atom_128x128x128_float32.rate8.zfp', range: [5, 100] },
};

const gpu = await requestNodeGpu({ label: 'bench.device', onFailure: (f) => console.error(`WebGPU ${f.kind}: ${f.message}`) });
const { device } = gpu;
const adapter = describeAdapter(gpu.adapter);
const scratch = mkdtempSync(join(tmpdir(), 'bench-iso-'));
const decoder = await ZfpDecoder.create(device);
console.log(`adapter: ${adapter}`);

interface VtkAnswer {
  filter: string;
  threads: number;
  backend: string;
  vtk: string;
  results: { iso: number; triangles: number; ms: number; samples: number[] }[];
}

/** Our GPU decode of the stream written as float32 raw, then VTK timed on it. */
async function vtkTimes(stream: ZfpGpuStream, isovalues: number[], name: string): Promise<VtkAnswer> {
  const raw = join(scratch, `${name}.f32`);
  const volume = (await decoder.readVolume(stream))!;
  writeFileSync(raw, new Uint8Array(volume.buffer, volume.byteOffset, volume.byteLength));
  const [x, y, z] = stream.info.dims;
  const out = execFileSync(
    join(root, '.venv', 'bin', 'python'),
    [
      join(root, 'tools', 'isosurface', 'vtk_flying_edges.py'),
      raw,
      `${x}`,
      `${y}`,
      `${z}`,
      '--repeats',
      `${repeats}`,
      '--iso',
      ...isovalues.map(String),
    ],
    { encoding: 'utf8', maxBuffer: 1 << 26 },
  );
  rmSync(raw);
  return JSON.parse(out);
}

const mean = (xs: number[]) => xs.reduce((a, b) => a + b, 0) / Math.max(1, xs.length);
const median = (xs: number[]) => {
  const s = [...xs].sort((a, b) => a - b);
  return s.length === 0 ? NaN : s.length % 2 ? s[s.length >> 1] : (s[s.length / 2 - 1] + s[s.length / 2]) / 2;
};

/** Mean ms per stage (records of the harness carry the whole IsosurfaceStats). */
function stageMeans(records: (BenchRecord | IsosurfaceStats)[]): Record<string, number> {
  const out: Record<string, number> = {};
  for (const r of records) for (const s of (r as IsosurfaceStats).stages) out[s.label] = (out[s.label] ?? 0) + s.ms / records.length;
  return out;
}

// ---- 1. the shared volumes
const volumeResults = [];
for (const name of volumeNames) {
  const spec = VOLUMES[name];
  if (!spec) throw new Error(`unknown volume ${name} (${Object.keys(VOLUMES).join(', ')})`);
  const stream = loadZfpStream(device, new Uint8Array(readFileSync(join(shared, spec.file))), spec.file);
  const iso = await Isosurface.create(gpu, stream);
  console.log(`\n${spec.file}: ${count} isovalues per mode in [${spec.range}], ${BENCH_MODES.join(', ')}`);
  const bench = await runBenchmark(iso, {
    modes: [...BENCH_MODES],
    count,
    range: spec.range,
    seed: 1,
    onProgress: (done, total) => {
      if (done % 25 === 0) console.log(`  ${done}/${total}`);
    },
  });
  iso.destroy();
  const isovalues = [...new Set(bench.records.map((r) => r.iso))];
  console.log(`  vtkFlyingEdges3D on ${isovalues.length} isovalues, ${repeats} repeats each`);
  const vtk = await vtkTimes(stream, isovalues, name);
  const vtkMs = new Map(vtk.results.map((r) => [Math.fround(r.iso), r]));
  const modes = BENCH_MODES.map((mode) => {
    const kept = bench.records.filter((r) => r.mode === mode && !r.discarded);
    const ours = kept.map((r) => r.gpuMs);
    const theirs = kept.map((r) => vtkMs.get(r.iso)!.ms);
    const mismatched = kept.filter((r) => vtkMs.get(r.iso)!.triangles !== r.triangles).length;
    return {
      mode,
      surfaces: kept.length,
      meanGpuMs: mean(ours),
      medianGpuMs: median(ours),
      meanWallMs: mean(kept.map((r) => r.wallMs)),
      hitRate: mean(kept.map((r) => r.hitRate)),
      meanActiveBlocks: mean(kept.map((r) => r.activeBlocks)),
      meanNewBlocks: mean(kept.map((r) => r.newBlocks)),
      meanTriangles: mean(kept.map((r) => r.triangles)),
      vtkMeanMs: mean(theirs),
      ratio: mean(ours) / mean(theirs),
      triangleCountsDifferingFromVtk: mismatched,
      stagesMeanMs: stageMeans(kept),
    };
  });
  volumeResults.push({
    volume: spec.file,
    dims: stream.info.dims,
    blocks: stream.info.blockCount,
    range: spec.range,
    vtk: { filter: vtk.filter, backend: vtk.backend, threads: vtk.threads, version: vtk.vtk },
    modes,
    records: bench.records,
  });
  printTable(
    `${spec.file} (${adapter}; VTK ${vtk.filter}, ${vtk.backend} ${vtk.threads} threads)`,
    ['mode', 'surfaces', 'GPU ms mean', 'median', 'hit rate %', 'active', 'new', 'triangles', 'VTK ms', 'ours / VTK'],
    modes.map((m) => [
      m.mode,
      m.surfaces,
      m.meanGpuMs,
      m.medianGpuMs,
      m.hitRate * 100,
      Math.round(m.meanActiveBlocks),
      Math.round(m.meanNewBlocks),
      Math.round(m.meanTriangles),
      m.vtkMeanMs,
      m.ratio,
    ]),
  );
  printTable(
    `${spec.file}: mean GPU ms per stage`,
    ['mode', ...Object.keys(modes[0].stagesMeanMs)],
    modes.map((m) => [m.mode, ...Object.values(m.stagesMeanMs)]),
  );
  stream.destroy();
}

// ---- 2. the same surface in a 64^3 and in a 512^3 volume
let embedding;
if (embed) {
  const small = 64;
  const large = 512;
  const offset = 192; // block-aligned: the 64^3 blocks compress to the same bits in both
  const sphere = new Float32Array(small ** 3);
  for (let z = 0; z < small; z++) {
    for (let y = 0; y < small; y++) {
      for (let x = 0; x < small; x++) sphere[x + small * (y + small * z)] = Math.fround(32 - Math.hypot(x - 31.5, y - 29.5, z - 33.5));
    }
  }
  const outside = -50;
  const big = new Float32Array(large ** 3).fill(outside);
  for (let z = 0; z < small; z++) {
    for (let y = 0; y < small; y++) {
      const at = offset + large * (offset + y + large * (offset + z));
      big.set(sphere.subarray(small * (y + small * z), small * (y + small * z + 1)), at);
    }
  }
  const isovalues = [4.37, 8.37, 12.37, 16.37, 20.37, 24.37];
  const runs = [];
  for (const [label, dims, data] of [
    ['64^3', [small, small, small], sphere],
    ['512^3', [large, large, large], big],
  ] as [string, Dims, Float32Array][]) {
    const stream = await compressOnGpu(device, new Uint8Array(data.buffer), 'float32', dims, 8, `sphere_${dims.join('x')}_float32.zfp`);
    const iso = await Isosurface.create(gpu, stream, { initialCacheSlots: 8192 });
    const cold: IsosurfaceStats[] = [];
    const warm: IsosurfaceStats[] = [];
    for (const t of isovalues) cold.push(await iso.compute(t));
    for (let r = 0; r < repeats; r++) for (const t of isovalues) warm.push(await iso.compute(t));
    iso.destroy();
    const vtk = await vtkTimes(stream, isovalues, `sphere${label}`);
    runs.push({
      label,
      dims,
      blocks: stream.info.blockCount,
      triangles: cold.map((s) => s.triangles),
      activeBlocks: cold.map((s) => s.activeBlocks),
      occupiedBlocks: cold.map((s) => s.occupiedBlocks),
      coldMeanGpuMs: mean(cold.map((s) => s.gpuMs)),
      warmMeanGpuMs: mean(warm.map((s) => s.gpuMs)),
      warmStagesMeanMs: stageMeans(warm),
      vtkMeanMs: mean(vtk.results.map((r) => r.ms)),
      vtkTriangles: vtk.results.map((r) => r.triangles),
    });
    stream.destroy();
  }
  if (runs[0].triangles.join() !== runs[1].triangles.join())
    throw new Error(`the embedded surfaces differ: ${runs[0].triangles} vs ${runs[1].triangles}`);
  embedding = { isovalues, offset, outside, rate: 8, runs };
  printTable(
    'the same sphere surfaces in 64^3 and in 512^3 (constant elsewhere), warm cache',
    [
      'volume',
      'blocks',
      'active (mean)',
      'triangles (mean)',
      'GPU ms warm',
      'GPU ms cold',
      ...Object.keys(runs[0].warmStagesMeanMs),
      'VTK ms',
    ],
    runs.map((r) => [
      r.label,
      r.blocks,
      mean(r.activeBlocks),
      mean(r.triangles),
      r.warmMeanGpuMs,
      r.coldMeanGpuMs,
      ...Object.values(r.warmStagesMeanMs),
      r.vtkMeanMs,
    ]),
  );
}

rmSync(scratch, { recursive: true, force: true });
decoder.destroy();
const tag = gpu.adapter.software ? 'swiftshader' : (gpu.adapter.vendor || 'gpu').replace(/\W+/g, '-');
writeJson(join(root, 'benchmarks', 'results', `isosurface-${tag}.json`), {
  date: new Date().toISOString(),
  adapter: gpu.adapter,
  adapterDescription: adapter,
  timing: 'GPU time from timestamp queries between the pipeline stages (sum of stages); VTK: median wall time of Update() over repeats',
  count,
  repeats,
  volumes: volumeResults,
  embedding,
});
device.destroy();
