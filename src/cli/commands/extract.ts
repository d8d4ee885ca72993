// `extract IN --iso a,b,c [--rate R] [--cache-budget MB] [--ply PREFIX]`:
// isosurfaces of a volume with the GPU pipeline (src/isosurface/), one after
// the other with the block cache kept between them. IN is a zfp file or an
// uncompressed volume (raw `name_XxYxZ_dtype.raw`, NRRD), compressed on the
// GPU at --rate (default 8) first, or `default`: the page's built-in volume. Per isovalue: counts, cache behaviour,
// surface area and bounding box in voxel index space (voxel (i, j, k) at
// (i, j, k), as VTK places them), GPU time; --ply writes each soup.
import { readFileSync, writeFileSync } from 'node:fs';
import { basename } from 'node:path';
import { describeAdapter } from '../../gpu/device.ts';
import { Isosurface } from '../../isosurface/isosurface.ts';
import { soupToPly } from '../../isosurface/ply.ts';
import { IsosurfaceBudgetError } from '../../isosurface/types.ts';
import { decodeVertices } from '../../isosurface/vertex-format.ts';
import { loadVolumeInput, VolumeInputError } from '../../isosurface/volume-input.ts';
import { isDefaultVolume, openDefaultVolume } from '../../volume/open-volume.ts';
import { meshMetrics } from '../../mc/mesh-metrics.ts';
import { ZfpFormatError } from '../../zfp/format.ts';
import { numberListOption, numberOption, requiredPositional, stringOption, UsageError, type CliCommand } from '../command.ts';

export interface ExtractRecord {
  iso: number;
  triangles: number;
  vertices: number;
  activeBlocks: number;
  newBlocks: number;
  occupiedBlocks: number;
  hitRate: number;
  surfaceArea: number;
  bbox: { min: [number, number, number]; max: [number, number, number] } | null;
  gpuMs: number;
  stages: { label: string; ms: number }[];
  cacheSlots: number;
  grew: boolean;
  ply?: string;
}

/** --cache-budget MB -> bytes (shared with `bench`). */
export function budgetOption(args: Parameters<typeof numberOption>[0]): number | undefined {
  const mb = numberOption(args, 'cache-budget');
  if (mb === undefined) return undefined;
  if (!(mb > 0)) throw new UsageError('--cache-budget must be a positive number of MB');
  return mb * 2 ** 20;
}

/** Opens IN as a GPU zfp stream, with user mistakes as UsageErrors (shared with `bench`). */
export async function openInput(device: GPUDevice, path: string, rate: number | undefined) {
  if (rate !== undefined && !(rate > 0)) throw new UsageError('--rate must be positive');
  if (isDefaultVolume(path)) {
    // The page's built-in volume (src/volume/open-volume.ts): same field, same rate, same stream.
    const v = await openDefaultVolume(device, rate === undefined ? {} : { rate });
    return { stream: v.stream, how: `the built-in volume "${v.name}", ${v.dims.join('x')} float32 compressed on the GPU at rate ${v.rate}`, rate: v.rate };
  }
  const bytes = new Uint8Array(readFileSync(path));
  try {
    return await loadVolumeInput(device, bytes, basename(path), { rate });
  } catch (e) {
    if (e instanceof VolumeInputError || e instanceof ZfpFormatError) throw new UsageError(e.message);
    throw e;
  }
}

export const extractCommand: CliCommand = {
  name: 'extract',
  summary: 'isosurfaces on the GPU (block cache kept between isovalues): counts, area, bbox, GPU time; --ply soups',
  usage: 'extract IN --iso a,b,c [--rate R] [--cache-budget MB] [--ply PREFIX]',
  options: {
    iso: { type: 'string' },
    rate: { type: 'string' },
    'cache-budget': { type: 'string' },
    ply: { type: 'string' },
  },
  async run(ctx, args) {
    const input = requiredPositional(args, 0, 'IN (a zfp file or a raw volume)');
    const isovalues = numberListOption(args, 'iso');
    if (!isovalues || isovalues.length === 0) throw new UsageError('give the isovalues with --iso a,b,c');
    const budget = budgetOption(args);
    const plyPrefix = stringOption(args, 'ply');
    const gpu = await ctx.gpu();
    const volume = await openInput(gpu.device, input, numberOption(args, 'rate'));
    ctx.log(`${input}: ${volume.how}`);
    const iso = await Isosurface.create(gpu, volume.stream, budget === undefined ? {} : { memoryBudgetBytes: budget });
    const records: (ExtractRecord | { iso: number; error: string })[] = [];
    try {
      for (const value of isovalues) {
        let stats;
        try {
          stats = await iso.compute(value);
        } catch (e) {
          if (!(e instanceof IsosurfaceBudgetError)) throw e;
          ctx.log(`error: ${e.message}`);
          records.push({ iso: Math.fround(value), error: e.message });
          continue;
        }
        const packed = await iso.readVertices();
        const positions = decodeVertices(packed, packed.length / 2, iso.info);
        const m = meshMetrics(positions);
        const record: ExtractRecord = {
          iso: stats.isovalue,
          triangles: stats.triangles,
          vertices: stats.vertices,
          activeBlocks: stats.activeBlocks,
          newBlocks: stats.newBlocks,
          occupiedBlocks: stats.occupiedBlocks,
          hitRate: stats.hitRate,
          surfaceArea: m.area,
          bbox: m.bbox,
          gpuMs: stats.gpuMs,
          stages: stats.stages,
          cacheSlots: stats.cacheSlots,
          grew: stats.grew,
        };
        if (plyPrefix) {
          record.ply = `${plyPrefix}-iso${stats.isovalue}.ply`;
          writeFileSync(record.ply, soupToPly(positions, `iso ${stats.isovalue} of ${basename(input)}, voxel index space`));
        }
        records.push(record);
        ctx.log(
          `iso ${stats.isovalue}: ${stats.triangles} triangles, ${stats.activeBlocks} active / ${stats.newBlocks} new / ${stats.occupiedBlocks} occupied blocks, ` +
            `hit rate ${(stats.hitRate * 100).toFixed(1)}%, area ${m.area.toFixed(2)}, ${stats.gpuMs.toFixed(1)} ms GPU (${stats.timingSource})${record.ply ? ` -> ${record.ply}` : ''}`,
        );
      }
    } finally {
      iso.destroy();
      volume.stream.destroy();
    }
    return {
      input,
      how: volume.how,
      dims: iso.info.dims,
      blockGrid: iso.info.blockGrid,
      valueRange: iso.info.valueRange,
      adapter: describeAdapter(gpu.adapter),
      memoryBudgetBytes: iso.memoryBudget,
      isosurfaces: records,
    };
  },
};
