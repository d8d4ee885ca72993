// bench:gpu's surfaces: the block-compressed isosurface pipeline (Isosurface:
// active blocks, LRU cache of decoded blocks, block marching cubes) through
// the shared harness with the original paper's sequences (random, sweep up,
// sweep down, each from a cold cache, first surface discarded), GPU time per
// surface and per stage from timestamps; and the naive data-parallel GPU
// marching cubes over the decoded volume on the first random isovalues, for
// the ratio. Volumes: the reference file (its triangle counts at the
// reference isovalues equal vtkMarchingCubes', shared/data/reference/mc.json,
// for both methods) and the converter's generated field compressed on the GPU
// (the naive MC's counts equal the block pipeline's, and one isovalue equals
// the serial CPU marching cubes over the decoded field).
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { BENCH_MODES } from '../../src/bench/sequences.ts';
import { Isosurface } from '../../src/isosurface/isosurface.ts';
import { NaiveMarchingCubes } from '../../src/mc/naive-gpu.ts';
import { marchingCubes } from '../../src/mc/serial-mc.ts';
import { compressOnGpu, openVolumeBytes } from '../../src/volume/open-volume.ts';
import { ZfpDecoder } from '../../src/zfp/decoder.ts';
import type { ZfpGpuStream } from '../../src/zfp/gpu-stream.ts';
import { runBlock } from '../paper/block.ts';
import type { PreparedVolume } from '../paper/volumes.ts';
import type { BenchRun } from './context.ts';
import { generatedField } from './gen-field.ts';
import { referenceEntry } from './zfp-decode.ts';

const SECTION = 'surfaces';
const SEED = 20200914;

interface VtkSurface {
  iso: number;
  vtkMarchingCubes: { triangles: number };
}

interface SurfaceVolume {
  key: string;
  stream: ZfpGpuStream;
  dims: [number, number, number];
  range: [number, number];
  /** VTK's triangle counts at the reference isovalues (reference file). */
  vtk?: VtkSurface[];
  /** The decoded field, for the serial CPU reference (generated volume). */
  values?: Float32Array;
}

async function referenceVolume(run: BenchRun): Promise<SurfaceVolume> {
  const file = run.plan.referenceVolume;
  const entry = referenceEntry(run.paths.data, file) as unknown as { isosurfaces: VtkSurface[] };
  const bytes = new Uint8Array(readFileSync(join(run.paths.data, 'volumes', file)));
  // a raw float32 file (fuel) is compressed on the GPU at rate 8, lossless for it, so VTK's counts on the raw file hold
  const opened = await openVolumeBytes(run.gpu.device, bytes, file, { rate: 8 });
  const isos = entry.isosurfaces.map((s) => s.iso);
  return {
    key: file,
    stream: opened.stream,
    dims: [...opened.stream.info.dims] as [number, number, number],
    range: [Math.min(...isos), Math.max(...isos)],
    vtk: entry.isosurfaces,
  };
}

async function generatedVolume(run: BenchRun, decoder: ZfpDecoder): Promise<SurfaceVolume> {
  const g = run.plan.genEdge;
  const dims: [number, number, number] = [g, g, g];
  const field = generatedField(dims);
  const key = `gen ${g}^3 (rate ${run.plan.genRate})`;
  const stream = await compressOnGpu(run.gpu.device, new Uint8Array(field.buffer), 'float32', dims, run.plan.genRate, key);
  // the decoded field for the serial CPU MC, which takes seconds per 256^3: only on small volumes (the smoke run's)
  const values = g <= 256 ? (await decoder.readVolume(stream))! : undefined;
  let lo = Infinity,
    hi = -Infinity;
  for (const v of field) {
    if (v < lo) lo = v;
    if (v > hi) hi = v;
  }
  // the middle 80% of the value range: surfaces through the whole volume, none empty
  return { key, stream, dims, range: [lo + 0.1 * (hi - lo), hi - 0.1 * (hi - lo)], values };
}

export async function surfacesSection(run: BenchRun): Promise<unknown> {
  const { gpu } = run;
  const decoder = await ZfpDecoder.create(gpu.device);
  const rows: (string | number)[][] = [];
  const stageRows: (string | number)[][] = [];
  const out: unknown[] = [];
  try {
    for (const make of [referenceVolume, (r: BenchRun) => generatedVolume(r, decoder)]) {
      const v = await make(run);
      try {
        out.push(await oneVolume(run, decoder, v, rows, stageRows));
      } finally {
        v.stream.destroy();
      }
    }
  } finally {
    decoder.destroy();
  }
  run.table({
    title: `isosurfaces: block-compressed pipeline per mode and naive GPU MC (mean per surface after the first; ${gpu.features.timestampQuery ? 'GPU timestamps' : 'queue wall time'})`,
    header: ['volume', 'method', 'surfaces', 'GPU ms', 'wall ms', 'hit rate', 'triangles', 'naive / block'],
    rows,
  });
  run.table({
    title: 'block-compressed pipeline: GPU ms per stage (mean per surface)',
    header: ['volume', 'mode', 'stages'],
    rows: stageRows,
  });
  return out;
}

async function oneVolume(
  run: BenchRun,
  decoder: ZfpDecoder,
  v: SurfaceVolume,
  rows: (string | number)[][],
  stageRows: (string | number)[][],
): Promise<unknown> {
  const { gpu, plan } = run;
  console.log(`  ${v.key}: range ${v.range.map((x) => x.toFixed(3)).join('..')}`);
  const volumeBuffer = decoder.decodeVolume(v.stream);
  const naive = await NaiveMarchingCubes.create(gpu.device, { dims: v.dims });
  try {
    // outside truth first: VTK's counts at the reference isovalues
    if (v.vtk) {
      const iso = await Isosurface.create(gpu, v.stream);
      try {
        for (const s of v.vtk) {
          const block = (await iso.compute(s.iso)).triangles;
          const nv = (await naive.extract(volumeBuffer, s.iso)).triangles;
          const want = s.vtkMarchingCubes.triangles;
          run.check(
            SECTION,
            `${v.key} iso ${s.iso.toFixed(2)}: block and naive MC equal vtkMarchingCubes`,
            block === want && nv === want,
            `block ${block}, naive ${nv}, VTK ${want} triangles`,
          );
        }
      } finally {
        iso.destroy();
      }
    }
    const naiveRuns: { iso: number; gpuMs: number; triangles: number }[] = [];
    const prepared = { key: v.key, stream: v.stream, range: v.range } as unknown as PreparedVolume;
    const b = await runBlock(gpu, prepared, [...BENCH_MODES], plan.surfacesPerMode, SEED, {
      capSecondsPerMode: plan.modeCapSeconds,
      pairRandom: async (iso, index) => {
        if (index >= plan.naiveSurfaces) return undefined;
        const t0 = performance.now();
        const r = await naive.extract(volumeBuffer, iso);
        naiveRuns.push({ iso, gpuMs: r.gpuMs, triangles: r.triangles });
        return performance.now() - t0;
      },
    });
    const random = b.records.filter((r) => r.mode === 'random');
    const pairs = naiveRuns.map((n, i) => ({ naive: n.triangles, block: random[i]?.triangles }));
    const same = pairs.every((p) => p.naive === p.block);
    run.check(
      SECTION,
      `${v.key}: naive MC equals the block pipeline on ${pairs.length} random isovalues`,
      same && pairs.length > 0,
      same ? `${pairs.map((p) => p.block).join(', ')} triangles` : JSON.stringify(pairs),
    );
    if (v.values) {
      const iso0 = random[0].iso;
      const cpu = marchingCubes(v.values, v.dims, iso0).triangleCount;
      run.check(
        SECTION,
        `${v.key} iso ${iso0.toFixed(4)}: the block pipeline equals the serial CPU MC`,
        cpu === random[0].triangles,
        `GPU ${random[0].triangles}, CPU ${cpu} triangles`,
      );
    }
    let blockRandomMs = NaN;
    for (const s of b.summaries) {
      if (s.mode === 'random') blockRandomMs = s.meanMs;
      run.figure(SECTION, `${v.key} ${s.mode}: GPU ms per surface`, s.meanMs, 'ms');
      run.figure(SECTION, `${v.key} ${s.mode}: wall ms per surface`, s.meanWallMs, 'ms');
      rows.push([v.key, `block ${s.mode}`, s.count, s.meanMs, s.meanWallMs, s.meanHitRate, Math.round(s.meanTriangles), '']);
      const stages = b.stages[s.mode] ?? {};
      stageRows.push([
        v.key,
        s.mode,
        Object.entries(stages)
          .map(([k, ms]) => `${k} ${ms.toFixed(3)}`)
          .join(', '),
      ]);
    }
    const kept = naiveRuns.slice(1);
    const naiveMs = kept.reduce((a, r) => a + r.gpuMs, 0) / Math.max(1, kept.length);
    const ratio = naiveMs / blockRandomMs;
    run.figure(SECTION, `${v.key} naive GPU MC: GPU ms per surface`, naiveMs, 'ms');
    run.figure(SECTION, `${v.key} naive / block (random mode)`, ratio, 'x');
    rows.push([
      v.key,
      'naive GPU MC',
      kept.length,
      naiveMs,
      '',
      '',
      Math.round(kept.reduce((a, r) => a + r.triangles, 0) / Math.max(1, kept.length)),
      ratio,
    ]);
    return {
      volume: v.key,
      dims: v.dims,
      range: v.range,
      summaries: b.summaries,
      stages: b.stages,
      memory: b.memory,
      naive: naiveRuns,
      naiveMeanGpuMs: naiveMs,
    };
  } finally {
    naive.destroy();
    volumeBuffer.destroy();
  }
}
