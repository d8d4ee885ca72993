// `bench IN [--modes random,sweep-up,sweep-down] [--count 100] [--seed S]
// [--range lo,hi] [--rate R] [--cache-budget MB]`: the paper's isosurface
// benchmark (section 4.6) with the shared harness (src/bench/harness.ts), the
// same one the page's benchmark panel runs: per mode a cold cache and a seeded
// isovalue sequence, the first surface discarded from the summaries. Prints a
// summary per mode; --json writes {volume, adapter, options, records, summaries}.
// --draw rays|mesh [--size WxH] (a volume opened whole): after each surface
// one image drawn offscreen at the Fit view, as `render` draws it (the same
// scene, src/cli/scene.ts, and renderOffscreen): each record gets the frame's
// GPU ms and the time per image (surface + frame), the table their mean and
// median. Rays read the block cache only, so their surfaces make no triangles
// (as `render`'s: IsosurfaceOptions.cacheOnly; triangles and occupied blocks 0).
import { describeAdapter } from '../../gpu/device.ts';
import { runBenchmark, type SurfaceEngine } from '../../bench/harness.ts';
import type { Isosurface } from '../../isosurface/isosurface.ts';
import type { IsosurfaceStats } from '../../isosurface/types.ts';
import { ArcballCamera } from '../../render/camera.ts';
import { createFrameBindGroupLayout } from '../../render/viewer.ts';
import { isStoreInput } from '../../store/cli-input.ts';
import { BENCH_MODES, isBenchMode, type BenchMode } from '../../bench/sequences.ts';
import { numberListOption, numberOption, requiredPositional, stringOption, UsageError, type CliCommand } from '../command.ts';
import { openInputSurface } from '../input.ts';
import { destroyScene, fitWhole, type Scene, wholeScene, wholeSceneAt } from '../scene.ts';
import { renderOffscreen } from '../../render/offscreen.ts';
import { sizeOption } from './render.ts';
import { budgetOption, deadlineOption, streamBudgetOption } from './extract.ts';
import { rateErrorRecord } from '../../zfp/rate-choice.ts';

function modesOption(text: string | undefined): BenchMode[] {
  if (text === undefined) return [...BENCH_MODES];
  const modes = text.split(',').map((s) => s.trim());
  for (const m of modes) if (!isBenchMode(m)) throw new UsageError(`--modes takes ${BENCH_MODES.join(', ')} (got "${m}")`);
  return modes as BenchMode[];
}

function pad(cells: (string | number)[], widths: number[]): string {
  return cells.map((c, i) => (typeof c === 'number' ? String(c).padStart(widths[i]) : c.padEnd(widths[i]))).join('  ');
}

export const benchCommand: CliCommand = {
  name: 'bench',
  summary: 'isosurface benchmark: random / sweep-up / sweep-down isovalues, GPU ms and hit rates per mode (--draw: and the time per image)',
  usage:
    "bench IN [--modes random,sweep-up,sweep-down] [--count N] [--seed S] [--range lo,hi] [--draw rays|mesh] [--size WxH] [--rate R | --stream-budget MB] [--cache-budget MB] [--level L] [--deadline S] [--time T] [--channel C] [--ranges RANGES.zarr] (--draw: one image per surface, offscreen at the Fit view, WxH default 1280x720, as render draws it: frame and image ms; a volume opened whole; rays make no triangles; --level, --deadline, --time, --channel, --ranges: IN a Zarr store URL or folder; --rate for a store: its lossless chunks' GPU rate, default 8)",
  options: {
    draw: { type: 'string' },
    size: { type: 'string' },
    level: { type: 'string' },
    deadline: { type: 'string' },
    time: { type: 'string' },
    channel: { type: 'string' },
    ranges: { type: 'string' },
    modes: { type: 'string' },
    count: { type: 'string' },
    seed: { type: 'string' },
    range: { type: 'string' },
    rate: { type: 'string' },
    'stream-budget': { type: 'string' },
    'cache-budget': { type: 'string' },
  },
  async run(ctx, args) {
    const input = requiredPositional(args, 0, 'IN (a zfp file or a raw volume)');
    const modes = modesOption(stringOption(args, 'modes'));
    const count = numberOption(args, 'count') ?? 100;
    if (!Number.isInteger(count) || count < 1) throw new UsageError('--count must be a positive integer');
    const seed = numberOption(args, 'seed') ?? 1;
    if (!Number.isInteger(seed)) throw new UsageError('--seed must be an integer');
    const rangeList = numberListOption(args, 'range');
    if (rangeList && (rangeList.length !== 2 || !(rangeList[0] < rangeList[1]))) throw new UsageError('--range must be lo,hi with lo < hi');
    const draw = stringOption(args, 'draw');
    if (draw !== undefined && draw !== 'rays' && draw !== 'mesh') throw new UsageError(`--draw ${draw}: rays or mesh`);
    const sizeText = stringOption(args, 'size');
    if (sizeText !== undefined && draw === undefined) throw new UsageError('--size is for --draw rays|mesh');
    const [width, height] = sizeOption(sizeText ?? '1280x720');
    if (draw !== undefined && isStoreInput(input))
      throw new UsageError('--draw is for a volume opened whole (not yet a Zarr store: `render` draws one of its views)');
    const budget = budgetOption(args);
    const gpu = await ctx.gpu();
    const volume = await openInputSurface(ctx, gpu, input, {
      rate: numberOption(args, 'rate'),
      level: numberOption(args, 'level'),
      budget,
      deadlineMs: deadlineOption(args),
      time: numberOption(args, 'time'),
      channel: numberOption(args, 'channel'),
      ranges: stringOption(args, 'ranges'),
      maxStreamBytes: streamBudgetOption(args),
      // rays read the block cache only (as render's): no triangles, no vertex memory
      ...(draw === 'rays' ? { cacheOnly: true } : {}),
    });
    ctx.log(`${input}: ${volume.how}`);
    const { iso } = volume;
    let scene: Scene | undefined;
    let frameTiming: 'timestamp-query' | 'wall' | undefined;
    try {
      // --draw: the harness draws one image after each surface, offscreen at the Fit view, as render draws it
      let engine: SurfaceEngine = iso;
      if (draw !== undefined) {
        const surface = iso as Isosurface;
        const { voxelSize, origin } = volume.placement;
        const camera = new ArcballCamera();
        fitWhole(camera, surface.info.dims, voxelSize, origin);
        const frameLayout = createFrameBindGroupLayout(gpu.device);
        const target = { device: gpu.device, format: 'rgba8unorm' as GPUTextureFormat, frameBindGroupLayout: frameLayout, camera };
        let last: IsosurfaceStats | undefined;
        engine = {
          resetCache: () => surface.resetCache(),
          compute: async (v) => {
            last = await surface.compute(v);
            return last;
          },
          draw: async () => {
            if (!last) throw new Error('bench: a frame before any surface');
            if (scene) wholeSceneAt(scene, last);
            else scene = await wholeScene(target, surface, last, draw, voxelSize, origin);
            const frame = await renderOffscreen(gpu.device, frameLayout, camera, width, height, scene.layer, { pixels: false });
            frameTiming = frame.timing;
            return frame.ms;
          },
        };
      }
      // Default range: the middle 80% of the values (the paper excludes noise and near-empty surfaces).
      const [lo, hi] = iso.info.valueRange;
      const range: [number, number] = rangeList ? [rangeList[0], rangeList[1]] : [lo + 0.1 * (hi - lo), hi - 0.1 * (hi - lo)];
      const result = await runBenchmark(engine, {
        modes,
        count,
        range,
        seed,
        onProgress: (done, total, r) => {
          if (done % 10 === 0 || done === total)
            ctx.log(
              `${done}/${total} ${r.mode} iso ${r.iso.toFixed(3)}: ${r.gpuMs.toFixed(1)} ms GPU` +
                `${r.frameMs === undefined ? '' : `, frame ${r.frameMs.toFixed(1)} ms`}, hit rate ${(r.hitRate * 100).toFixed(1)}%`,
            );
        },
      });
      const ms = (x: number | undefined) => (x ?? Number.NaN).toFixed(1);
      const header = [
        'mode',
        'surfaces',
        'mean ms',
        'median ms',
        'wall ms',
        ...(draw ? [`${draw} frame ms`, 'median', 'image ms', 'median'] : []),
        'hit rate %',
        'active',
        'new',
        'occupied',
        'triangles',
      ];
      const rows = result.summaries.map((s) => [
        s.mode,
        s.count,
        s.meanMs.toFixed(1),
        s.medianMs.toFixed(1),
        s.meanWallMs.toFixed(1),
        ...(draw ? [ms(s.meanFrameMs), ms(s.medianFrameMs), ms(s.meanImageMs), ms(s.medianImageMs)] : []),
        (s.meanHitRate * 100).toFixed(2),
        Math.round(s.meanActiveBlocks),
        Math.round(s.meanNewBlocks),
        Math.round(s.meanOccupiedBlocks),
        Math.round(s.meanTriangles),
      ]);
      const widths = header.map((h, i) => Math.max(h.length, ...rows.map((r) => String(r[i]).length)));
      console.log(
        `\n${input} (${iso.info.dims.join('x')}), ${count} isovalues per mode in [${range[0]}, ${range[1]}], seed ${seed}, ${describeAdapter(gpu.adapter)}` +
          (draw
            ? `; one ${width}x${height} image per surface by ${draw} (frame: ${frameTiming === 'wall' ? 'queue wall time' : 'GPU timestamps'}; image = surface + frame)`
            : ''),
      );
      console.log(pad(header, widths));
      for (const r of rows) console.log(pad(r, widths));
      return {
        volume: { file: input, how: volume.how, dims: iso.info.dims, blockCount: iso.info.blockCount, valueRange: iso.info.valueRange },
        adapter: describeAdapter(gpu.adapter),
        options: {
          ...result.options,
          rate: volume.rate,
          memoryBudgetBytes: iso.memoryBudget,
          ...(draw ? { draw, size: [width, height], frameTiming: frameTiming === 'wall' ? 'queue-wall-time' : 'timestamp-query' } : {}),
        },
        rate: volume.rate,
        rateError: volume.rateChoice ? rateErrorRecord(volume.rateChoice) : null,
        records: result.records,
        summaries: result.summaries,
        ...(volume.store ? { store: volume.store() } : {}),
      };
    } finally {
      destroyScene(scene);
      volume.destroy();
    }
  },
};
