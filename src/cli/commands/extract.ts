// `extract IN --iso a,b,c [--rate R] [--cache-budget MB] [--ply PREFIX]`:
// isosurfaces of a volume with the GPU pipeline (src/isosurface/), one after
// the other with the block cache kept between them. IN is a zfp file or an
// uncompressed volume (raw `name_XxYxZ_dtype.raw`, NRRD, TIFF stack),
// compressed on the GPU at --rate (default 8) first, or `default`: the page's
// built-in volume; opened as the page opens it (src/volume/open-volume.ts).
// Per isovalue: counts, cache behaviour, surface area and bounding box in
// voxel index space (voxel (i, j, k) at (i, j, k), as VTK places them), GPU
// time; --ply writes each soup. A surface over the memory budget is recorded
// as {iso, error}, the others are still computed, and the exit status is 1.
import { readFileSync, writeFileSync } from 'node:fs';
import { basename } from 'node:path';
import { describeAdapter } from '../../gpu/device.ts';
import { Isosurface } from '../../isosurface/isosurface.ts';
import { encodePly, weldVertices } from '../../mc/ply.ts';
import { formatMB } from '../../isosurface/budget.ts';
import { IsosurfaceBudgetError } from '../../isosurface/types.ts';
import { decodeVertices } from '../../isosurface/vertex-format.ts';
import { checkValueRange, describeOpenedVolume, isDefaultVolume, openDefaultVolume, openVolumeBytes, VolumeFileError } from '../../volume/open-volume.ts';
import { meshMetrics } from '../../mc/mesh-metrics.ts';
import { ZfpFormatError } from '../../zfp/format.ts';
import { isStoreInput, openStoreInput } from '../../store/cli-input.ts';
import { StoreError } from '../../store/zarr/errors.ts';
import { CommandFailed, numberListOption, numberOption, requiredPositional, stringOption, UsageError, type CliCommand } from '../command.ts';

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

/**
 * The pipeline for an opened input, refusing (UsageError, exit status 2) a
 * volume without finite values; logs what the user should know (NaN/Inf
 * replaced). Frees the stream on failure (shared with `bench`).
 */
export async function createInputIsosurface(ctx: { log(m: string): void }, gpu: Parameters<typeof Isosurface.create>[0], volume: Awaited<ReturnType<typeof openInput>>, budget: number | undefined) {
  for (const note of volume.notes) ctx.log(`note: ${note}`);
  let iso: Isosurface | undefined;
  try {
    iso = await Isosurface.create(gpu, volume.stream, budget === undefined ? {} : { memoryBudgetBytes: budget });
    checkValueRange(volume.fileName, iso.info.valueRange);
    return iso;
  } catch (e) {
    iso?.destroy();
    volume.stream.destroy();
    if (e instanceof VolumeFileError) throw new UsageError(e.message);
    throw e;
  }
}

/** --cache-budget MB -> bytes (shared with `bench`). */
export function budgetOption(args: Parameters<typeof numberOption>[0]): number | undefined {
  const mb = numberOption(args, 'cache-budget');
  if (mb === undefined) return undefined;
  if (!(mb > 0)) throw new UsageError('--cache-budget must be a positive number of MB');
  return mb * 2 ** 20;
}

/** Opens IN as a GPU zfp stream (src/volume/open-volume.ts, as the page does), with user mistakes as UsageErrors (shared with `bench`); a Zarr store (URL or folder) at --level L through src/store/. */
export async function openInput(device: GPUDevice, path: string, rate: number | undefined, level?: number, log: (m: string) => void = () => {}) {
  if (isStoreInput(path)) {
    try {
      return await openStoreInput(device, path, level, (m) => log(`error: ${m}`));
    } catch (e) {
      if (e instanceof StoreError || e instanceof ZfpFormatError) throw new UsageError(e.message);
      throw e;
    }
  }
  if (level !== undefined) throw new UsageError('--level is for a Zarr store (a URL or a folder with zarr.json)');
  if (rate !== undefined && !(rate > 0)) throw new UsageError('--rate must be positive');
  // `default`: the page's built-in volume, same field, same rate, same stream.
  let bytes: Uint8Array | undefined;
  if (!isDefaultVolume(path)) {
    try {
      bytes = new Uint8Array(readFileSync(path));
    } catch (e) {
      throw new UsageError(`cannot read ${path}: ${(e as Error).message}`);
    }
  }
  try {
    const v = bytes ? await openVolumeBytes(device, bytes, basename(path), { rate, reader: 'command' }) : await openDefaultVolume(device, rate === undefined ? {} : { rate });
    return { stream: v.stream, how: describeOpenedVolume(v), rate: v.rate, notes: v.notes, fileName: v.fileName };
  } catch (e) {
    if (e instanceof VolumeFileError || e instanceof ZfpFormatError) throw new UsageError(e.message);
    throw e;
  }
}

export const extractCommand: CliCommand = {
  name: 'extract',
  summary: 'isosurfaces on the GPU (block cache kept between isovalues): counts, area, bbox, GPU time; --ply soups',
  usage: 'extract IN --iso a,b,c [--rate R] [--cache-budget MB] [--ply PREFIX] [--level L (IN a Zarr store URL or folder)]',
  options: {
    level: { type: 'string' },
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
    const volume = await openInput(gpu.device, input, numberOption(args, 'rate'), numberOption(args, 'level'), (m) => ctx.log(m));
    ctx.log(`${input}: ${volume.how}`);
    const iso = await createInputIsosurface(ctx, gpu, volume, budget);
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
          writeFileSync(record.ply, encodePly(weldVertices(positions), [`iso ${stats.isovalue} of ${basename(input)}, voxel index space`]));
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
    const result = {
      input,
      how: volume.how,
      dims: iso.info.dims,
      blockGrid: iso.info.blockGrid,
      valueRange: iso.info.valueRange,
      notes: volume.notes,
      adapter: describeAdapter(gpu.adapter),
      memoryBudgetBytes: iso.memoryBudget,
      isosurfaces: records,
      ...('store' in volume ? { store: volume.store } : {}),
    };
    // Surfaces that did not fit are failures: the JSON still gets every record, then the exit status says so.
    const failed = records.filter((r): r is { iso: number; error: string } => 'error' in r);
    if (failed.length > 0) {
      throw new CommandFailed(
        `${failed.length} of ${records.length} isosurfaces did not fit the GPU memory budget of ${formatMB(iso.memoryBudget)} ` +
          `(iso ${failed.map((f) => f.iso).join(', ')}); raise it with --cache-budget MB`,
        result,
      );
    }
    return result;
  },
};
