// `extract IN --iso a,b,c [--rate R] [--cache-budget MB] [--ply PREFIX]`:
// isosurfaces of a volume with the GPU pipeline (src/isosurface/), one after
// the other with the block cache kept between them. IN is a zfp file or an
// uncompressed volume (raw `name_XxYxZ_dtype.raw`, NRRD, TIFF stack),
// compressed on the GPU first (at --rate, or the rate chosen from the data:
// src/zfp/rate-choice.ts; the record's `rate` and `rateError` say which and
// what error it gives), or `default`: the page's built-in volume; opened as
// the page opens it (src/volume/open-volume.ts).
// Per isovalue: counts, cache behaviour, surface area and bounding box in
// voxel index space (voxel (i, j, k) at (i, j, k), as VTK places them), GPU
// time; area and enclosed volume in physical units (the file's voxel size,
// a store's OME scale; src/mc/mesh-measure.ts); --ply writes each soup, --glb
// all surfaces as meshes of one binary glTF; --clip (a box of whole cells)
// and --plane (n . x >= d) cut every surface open before it is measured and
// written (src/core/clip.ts; a store leaves out chunks they remove whole). A surface over the memory budget is recorded
// as {iso, error}, the others are still computed, and the exit status is 1.
// A store with a t axis and `--time start:stop[:step]`: the same for each
// time point the slice selects, one after the other (extractSeries).
import { writeFileSync } from 'node:fs';
import { basename } from 'node:path';
import { describeAdapter } from '../../gpu/device.ts';
import { meteredGpu } from '../../gpu/memory-meter.ts';
import { encodePly, soupOf } from '../../mc/ply.ts';
import { formatMB } from '../../isosurface/budget.ts';
import { IsosurfaceBudgetError } from '../../isosurface/types.ts';
import { meshPositions } from '../../isosurface/vertex-format.ts';
import { meshMetrics } from '../../mc/mesh-metrics.ts';
import { measureSurface } from '../../mc/mesh-measure.ts';
import { encodeGlb, type GlbSurface, SURFACE_PALETTE } from '../../mc/glb.ts';
import { type Clip, clipMesh, parseClipBox, parseClipPlane } from '../../core/clip.ts';
import { LevelStoppedError } from '../../store/stream-surface.ts';
import { type OpenedInput, openInputSurface } from '../input.ts';
import { isStoreInput, storeTimeAxis } from '../../store/cli-input.ts';
import { type PrefetchState, SeriesPrefetch } from '../../store/series/prefetch.ts';
import { storeForLocation } from '../../store/zarr/node-store.ts';
import { openStore } from '../../store/zarr/open-store.ts';
import { type StoreTimeAxis, timeValueOf } from '../../store/zarr/store.ts';
import { StoreError } from '../../store/zarr/errors.ts';
import { ZfpFormatError } from '../../zfp/format.ts';
import { formatTimeSlice, isTimeSlice, parseTimeSlice, sliceIndices } from '../time-selection.ts';
import { parseCam } from '../../store/view/camera.ts';
import { type ViewRequest, parseViewBox } from '../../store/view/view-request.ts';
import type { CutChunkRecord } from '../../store/stream-surface.ts';
import { rateErrorRecord } from '../../zfp/rate-choice.ts';
import {
  type CliContext,
  CommandFailed,
  InputError,
  type ParsedArgs,
  numberListOption,
  numberOption,
  requiredPositional,
  stringOption,
  UsageError,
  type CliCommand,
} from '../command.ts';

export interface ExtractRecord {
  iso: number;
  triangles: number;
  /** Welded vertices (one per cut grid edge) and triangle corners. */
  vertices: number;
  indices: number;
  activeBlocks: number;
  newBlocks: number;
  occupiedBlocks: number;
  hitRate: number;
  /** Voxel index space (every voxel 1 on a side). */
  surfaceArea: number;
  /** Physical units (the result's voxelSize and unit): area, and the enclosed volume where the surface is closed (null where it is open). */
  area: number;
  enclosedVolume: number | null;
  /** Edges used more often in one direction than the other (welded by position): 0 when closed. */
  openEdges: number;
  /** With --clip / --plane: the triangles kept (area, volume, bbox and the files are of those). */
  clippedTriangles?: number;
  bbox: { min: [number, number, number]; max: [number, number, number] } | null;
  gpuMs: number;
  stages: { label: string; ms: number }[];
  cacheSlots: number;
  grew: boolean;
  ply?: string;
  /** The mesh of this surface in the --glb file. */
  glbMesh?: string;
  /** A store refined by a view: the chunks drawn per level, with the triangles of each (stitching geometry, if any, apart). */
  cut?: CutChunkRecord[];
  /** A store refined by a view: triangles besides the cut's regular cells (skirts over level seams), and GPU bytes held with this surface. */
  stitchTriangles?: number;
  gpuBytes?: number;
}

/** Voxel index positions -> physical ones: ((i, j, k) + origin) * voxelSize. */
function physicalPositions(positions: Float32Array, placement: { voxelSize: readonly number[]; origin: readonly number[] }): Float32Array {
  const out = new Float32Array(positions.length);
  for (let i = 0; i < positions.length; i++) out[i] = (positions[i] + placement.origin[i % 3]) * placement.voxelSize[i % 3];
  return out;
}

/** --deadline S (a store's per-request retry deadline) -> ms (shared with `bench`). */
export function deadlineOption(args: Parameters<typeof numberOption>[0]): number | undefined {
  const s = numberOption(args, 'deadline');
  if (s === undefined) return undefined;
  if (!(s > 0)) throw new UsageError('--deadline must be a positive number of seconds');
  return s * 1000;
}

/** --stream-budget MB -> bytes: the largest stream a rate chosen from the data may make (shared with `bench`). */
export function streamBudgetOption(args: Parameters<typeof numberOption>[0]): number | undefined {
  const mb = numberOption(args, 'stream-budget');
  if (mb === undefined) return undefined;
  if (!(mb > 0)) throw new UsageError('--stream-budget must be a positive number of MB');
  return mb * 2 ** 20;
}

/** --view-box / --view [--tolerance PX] -> the view a store is refined by (shared with `bench`). */
export function viewOption(args: Parameters<typeof numberOption>[0]): ViewRequest | undefined {
  const box = stringOption(args, 'view-box');
  const link = stringOption(args, 'view');
  const tolerancePx = numberOption(args, 'tolerance');
  const skirts = args.values['no-skirts'] === true ? false : undefined;
  if (box !== undefined && link !== undefined) throw new UsageError('give --view-box or --view, not both');
  if (tolerancePx !== undefined && !(tolerancePx > 0)) throw new UsageError('--tolerance must be a positive number of pixels');
  if (box === undefined && link === undefined) {
    if (tolerancePx !== undefined) throw new UsageError('--tolerance is for --view-box or --view');
    return undefined;
  }
  if (numberOption(args, 'level') !== undefined) throw new UsageError('--level pins one level; --view-box and --view refine by the view');
  if (box !== undefined) {
    const parsed = parseViewBox(box);
    if (typeof parsed === 'string') throw new UsageError(`--view-box ${box}: ${parsed}`);
    return { box: parsed, tolerancePx, skirts };
  }
  if (!parseCam(new URLSearchParams(link!.replace(/^.*#/, '')).get('cam') ?? ''))
    throw new UsageError(`--view ${link}: the page's link, with its camera (#iso=..&cam=qx,qy,qz,qw,tx,ty,tz,d[&px=W,H][&tol=T])`);
  return { link, tolerancePx, skirts };
}

/** --clip x0,y0,z0,x1,y1,z1 (grid points of level 0) and --plane nx,ny,nz,d -> the clip, or undefined. */
export function clipOption(args: Parameters<typeof numberOption>[0]): Clip | undefined {
  const boxText = stringOption(args, 'clip');
  const planeText = stringOption(args, 'plane');
  if (boxText === undefined && planeText === undefined) return undefined;
  const clip: Clip = {};
  if (boxText !== undefined) {
    const box = parseClipBox(boxText);
    if (typeof box === 'string') throw new UsageError(`--clip ${boxText}: ${box}`);
    if (!box.every(Number.isInteger))
      throw new UsageError(`--clip ${boxText}: the box's corners are grid points (whole voxel indices of level 0)`);
    clip.box = box;
  }
  if (planeText !== undefined) {
    const plane = parseClipPlane(planeText);
    if (typeof plane === 'string') throw new UsageError(`--plane ${planeText}: ${plane}`);
    clip.plane = plane;
  }
  return clip;
}

/** --cache-budget MB -> bytes (shared with `bench`). */
export function budgetOption(args: Parameters<typeof numberOption>[0]): number | undefined {
  const mb = numberOption(args, 'cache-budget');
  if (mb === undefined) return undefined;
  if (!(mb > 0)) throw new UsageError('--cache-budget must be a positive number of MB');
  return mb * 2 ** 20;
}

export const extractCommand: CliCommand = {
  name: 'extract',
  summary:
    'isosurfaces on the GPU (block cache kept between isovalues): counts, area, enclosed volume, bbox, GPU time; --ply soups, --glb glTF',
  usage:
    "extract IN --iso a,b,c [--rate R | --stream-budget MB] [--cache-budget MB] [--ply PREFIX] [--glb FILE] [--clip x0,y0,z0,x1,y1,z1] [--plane nx,ny,nz,d] [--level L] [--deadline S] [--time T | start:stop[:step]] [--channel C] [--ranges RANGES.zarr] [--view-box x0,y0,z0,x1,y1,z1 | --view '#iso=..&cam=..'] [--tolerance PX] [--no-skirts] [--save-ranges OUT.zarr] (--level, --view-box, --view, --deadline, --time, --channel, --ranges: IN a Zarr store URL or folder; --rate for a store: its lossless chunks' GPU rate, default 8; --save-ranges: a store of lossless chunks, the brick ranges learnt by these surfaces written as a ranges sidecar; --time start:stop[:step]: the time points of a store's t axis by Python's slice rule (0:20:2, ::-1, --time=-4: when it starts with '-'), one record per time point and isovalue with its `time`, --ply PREFIX-tT-isoV.ply per time point, a store of lossless chunks at the rate of the first time point unless --rate; the next time point's chunks fetched while one is computed, within --prefetch MB of CPU memory, default 256, 0: none)",
  options: {
    level: { type: 'string' },
    deadline: { type: 'string' },
    time: { type: 'string' },
    channel: { type: 'string' },
    ranges: { type: 'string' },
    view: { type: 'string' },
    'view-box': { type: 'string' },
    tolerance: { type: 'string' },
    'no-skirts': { type: 'boolean' },
    iso: { type: 'string' },
    rate: { type: 'string' },
    'stream-budget': { type: 'string' },
    'cache-budget': { type: 'string' },
    ply: { type: 'string' },
    glb: { type: 'string' },
    clip: { type: 'string' },
    plane: { type: 'string' },
    'save-ranges': { type: 'string' },
    prefetch: { type: 'string' },
  },
  async run(ctx, args) {
    const input = requiredPositional(args, 0, 'IN (a zfp file or a raw volume)');
    const isovalues = numberListOption(args, 'iso');
    if (!isovalues || isovalues.length === 0) throw new UsageError('give the isovalues with --iso a,b,c');
    const timeText = stringOption(args, 'time');
    if (timeText !== undefined && isTimeSlice(timeText)) return extractSeries(ctx, args, input, isovalues, timeText);
    const budget = budgetOption(args);
    const plyPrefix = stringOption(args, 'ply');
    const glbPath = stringOption(args, 'glb');
    const glbSurfaces: GlbSurface[] = [];
    const clip = clipOption(args);
    const saveRanges = stringOption(args, 'save-ranges');
    const device = await ctx.gpu();
    // everything this command makes on the GPU is metered: the record's peak
    const { gpu, meter } = meteredGpu(device);
    const volume = await openInputSurface(ctx, gpu, input, {
      rate: numberOption(args, 'rate'),
      level: numberOption(args, 'level'),
      budget,
      deadlineMs: deadlineOption(args),
      time: numberOption(args, 'time'),
      channel: numberOption(args, 'channel'),
      ranges: stringOption(args, 'ranges'),
      maxStreamBytes: streamBudgetOption(args),
      view: viewOption(args),
      clip,
    });
    ctx.log(`${input}: ${volume.how}`);
    if (saveRanges !== undefined && !volume.saveRanges) {
      volume.destroy();
      throw new UsageError('--save-ranges is for a Zarr store of lossless chunks (a zfp store has its own range arrays or none)');
    }
    const { iso } = volume;
    let records: SurfaceRecord[] = [];
    let storeRecord: ReturnType<NonNullable<typeof volume.store>> | undefined;
    let savedRanges: { path: string; known: number; bricks: number } | undefined;
    try {
      records = await surfacesOf(ctx, volume, isovalues, {
        input,
        clip,
        ply: plyPrefix === undefined ? undefined : (isoValue) => `${plyPrefix}-iso${isoValue}.ply`,
        glb: glbPath === undefined ? undefined : { surfaces: glbSurfaces, name: (isoValue) => `iso ${isoValue}` },
      });
      storeRecord = volume.store?.(); // before destroy: the GPU bytes held with the last surface
      if (saveRanges !== undefined && volume.saveRanges) {
        try {
          savedRanges = { path: saveRanges, ...(await volume.saveRanges(saveRanges)) };
        } catch (e) {
          throw new InputError(`--save-ranges ${saveRanges}: ${(e as Error).message}`, { cause: e });
        }
        ctx.log(`${saveRanges}: the ranges of ${savedRanges.known} of ${savedRanges.bricks} bricks (the others unknown: NaN)`);
      }
      if (glbPath !== undefined) await writeGlb(ctx, glbPath, glbSurfaces, input, volume.placement);
    } finally {
      volume.destroy();
    }
    const result = {
      input,
      how: volume.how,
      rate: volume.rate,
      rateError: volume.rateChoice ? rateErrorRecord(volume.rateChoice) : null,
      dims: iso.info.dims,
      blockGrid: iso.info.blockGrid,
      valueRange: iso.info.valueRange,
      voxelSize: volume.placement.voxelSize,
      origin: volume.placement.origin,
      unit: volume.placement.unit,
      ...(glbPath !== undefined ? { glb: glbPath } : {}),
      notes: volume.notes,
      adapter: describeAdapter(gpu.adapter),
      // the surfaces computed over one block cache (a store: in one refinement, from the same resident chunks), and (--glb) written together
      drawnTogether: records.filter((r): r is ExtractRecord => !('error' in r)).map((r) => r.iso),
      gpuPeakBytes: meter.peak,
      memoryBudgetBytes: iso.memoryBudget,
      isosurfaces: records,
      ...(storeRecord ? { store: storeRecord } : {}),
      ...(savedRanges ? { savedRanges } : {}),
    };
    failIfAnyFailed(records, iso.memoryBudget, result);
    return result;
  },
};

/** A surface's record, or why it could not be made. */
type FailedRecord = { iso: number; error: string; overBudget?: boolean };
type SurfaceRecord = ExtractRecord | FailedRecord;

/** Surfaces that did not fit or could not be fetched are failures: the JSON still gets every record, then the exit status says so. */
function failIfAnyFailed(records: readonly (SurfaceRecord & { time?: number })[], memoryBudget: number, result: unknown): void {
  const failed = records.filter((r): r is FailedRecord & { time?: number } => 'error' in r);
  if (failed.length === 0) return;
  const overBudget = failed.filter((f) => f.overBudget);
  const other = failed.filter((f) => !f.overBudget);
  const at = (f: { iso: number; time?: number }) => (f.time === undefined ? `${f.iso}` : `${f.iso} at t ${f.time}`);
  const parts: string[] = [];
  if (overBudget.length > 0)
    parts.push(
      `${overBudget.length} did not fit the GPU memory budget of ${formatMB(memoryBudget)} (iso ${overBudget.map(at).join(', ')}); raise it with --cache-budget MB`,
    );
  for (const f of other) parts.push(`iso ${at(f)}: ${f.error}`);
  throw new CommandFailed(`${failed.length} of ${records.length} isosurfaces failed: ${parts.join('; ')}`, result);
}

async function writeGlb(
  ctx: { log(m: string): void },
  glbPath: string,
  glbSurfaces: GlbSurface[],
  input: string,
  placement: OpenedInput['placement'],
): Promise<void> {
  const unit = placement.unit;
  const glb = await encodeGlb(glbSurfaces, {
    generator: 'zfp-isosurface-webgpu extract',
    extras: { source: basename(input), voxelSize: placement.voxelSize, unit },
  });
  writeFileSync(glbPath, glb);
  ctx.log(`${glbPath}: ${glbSurfaces.length} surfaces (${unit ?? 'units of the voxel size'})`);
}

/**
 * Every isovalue's surface over one opened volume (a store draws them
 * together: one refinement, a chunk fetched when any of them needs it):
 * measured, written (--ply, --glb) and logged; one over the budget or whose
 * chunks could not be fetched is recorded as {iso, error}.
 */
async function surfacesOf(
  ctx: { log(m: string): void },
  volume: OpenedInput,
  isovalues: readonly number[],
  out: {
    input: string;
    clip: Clip | undefined;
    /** The PLY file of a surface, or undefined for none. */
    ply: ((iso: number) => string) | undefined;
    glb: { surfaces: GlbSurface[]; name: (iso: number) => string } | undefined;
    /** Words before each log line (a series: the time point). */
    logPrefix?: string;
  },
): Promise<SurfaceRecord[]> {
  const { iso } = volume;
  const records: SurfaceRecord[] = [];
  const { clip } = out;
  const logPrefix = out.logPrefix ?? '';
  if ('together' in iso) iso.together(isovalues);
  for (const value of isovalues) {
    let stats;
    try {
      stats = await iso.compute(value);
    } catch (e) {
      if (!(e instanceof IsosurfaceBudgetError) && !(e instanceof LevelStoppedError)) throw e;
      ctx.log(`error: ${logPrefix}${e.message}`);
      const budget = e instanceof IsosurfaceBudgetError || (e instanceof LevelStoppedError && e.overBudget);
      records.push({ iso: Math.fround(value), error: e.message, ...(budget ? { overBudget: true } : {}) });
      continue;
    }
    let welded: Float32Array;
    let indices: Uint32Array;
    let cut: CutChunkRecord[] | undefined;
    if ('readPositions' in iso) {
      // a store: positions in the pinned level's voxels, or (a view's cut) in level-0 voxels with each level placed by its metadata, and the cut
      ({ positions: welded, indices } = await iso.readPositions(value));
      cut = await iso.cutRecord(value);
    } else {
      const surface = await iso.readMesh();
      welded = meshPositions(surface);
      indices = surface.indices;
    }
    if (clip) ({ positions: welded, indices } = clipMesh(welded, indices, clip));
    const m = meshMetrics(soupOf(welded, indices));
    const measure = measureSurface(welded, indices, volume.placement);
    const record: ExtractRecord = {
      iso: stats.isovalue,
      triangles: stats.triangles,
      vertices: stats.vertices,
      indices: stats.indices,
      activeBlocks: stats.activeBlocks,
      newBlocks: stats.newBlocks,
      occupiedBlocks: stats.occupiedBlocks,
      hitRate: stats.hitRate,
      surfaceArea: m.area,
      area: measure.area,
      enclosedVolume: measure.enclosedVolume,
      openEdges: measure.openEdges,
      ...(clip ? { clippedTriangles: indices.length / 3 } : {}),
      bbox: m.bbox,
      gpuMs: stats.gpuMs,
      stages: stats.stages,
      cacheSlots: stats.cacheSlots,
      grew: stats.grew,
      ...(cut
        ? { cut, stitchTriangles: stats.triangles - cut.reduce((a, e) => a + e.triangles, 0), gpuBytes: volume.store?.().gpuBytes }
        : {}),
    };
    if (out.ply) {
      record.ply = out.ply(stats.isovalue);
      writeFileSync(
        record.ply,
        encodePly({ positions: welded, indices }, [
          `iso ${stats.isovalue} of ${basename(out.input)}${logPrefix ? `, ${logPrefix.replace(/: $/, '')}` : ''}, ${cut ? 'level-0 voxel index space (levels placed by their OME translation)' : 'voxel index space'}`,
        ]),
      );
    }
    if (out.glb && indices.length > 0) {
      record.glbMesh = out.glb.name(stats.isovalue);
      out.glb.surfaces.push({
        name: record.glbMesh,
        positions: physicalPositions(welded, volume.placement),
        indices,
        color: SURFACE_PALETTE[out.glb.surfaces.length % SURFACE_PALETTE.length],
        opacity: 1,
        extras: { isovalue: stats.isovalue, area: measure.area, enclosedVolume: measure.enclosedVolume },
      });
    }
    records.push(record);
    ctx.log(
      `${logPrefix}iso ${stats.isovalue}: ${stats.triangles} triangles, ${stats.activeBlocks} active / ${stats.newBlocks} new / ${stats.occupiedBlocks} occupied blocks, ` +
        `hit rate ${(stats.hitRate * 100).toFixed(1)}%, area ${measure.area.toPrecision(6)}, ${measure.enclosedVolume === null ? `open (${measure.openEdges} open edges)` : `encloses ${measure.enclosedVolume.toPrecision(6)}`}, ${stats.gpuMs.toFixed(1)} ms GPU (${stats.timingSource})${record.ply ? ` -> ${record.ply}` : ''}`,
    );
  }
  return records;
}

/** A time point of a series: its index, and its physical time and unit when the store's OME metadata give them. */
interface TimeOfRecord {
  time: number;
  timeValue?: number;
  timeUnit?: string;
}

/**
 * `extract STORE --time start:stop[:step]`: the surfaces at every isovalue
 * for each time point the slice selects (Python's rule, against the store's
 * t count), one time point after the other on the one GPU device; each time
 * point's store session and surfaces are destroyed before the next opens
 * (the record's `gpuBytesAfter` says what was left: 0). Without --rate, a
 * store of lossless chunks keeps the rate chosen at the first time point
 * for the rest, so the series is one decode.
 */
async function extractSeries(ctx: CliContext, args: ParsedArgs, input: string, isovalues: number[], timeText: string): Promise<unknown> {
  const slice = parseTimeSlice(timeText);
  if (typeof slice === 'string') throw new UsageError(`--time ${timeText}: ${slice}`);
  if (!isStoreInput(input))
    throw new UsageError('--time is for a Zarr store (a URL or a folder with zarr.json); a time series is a store with a t axis');
  if (stringOption(args, 'save-ranges') !== undefined)
    throw new UsageError('--save-ranges writes the ranges of one time point: give --time as one index');
  const budget = budgetOption(args);
  const plyPrefix = stringOption(args, 'ply');
  const glbPath = stringOption(args, 'glb');
  const glbSurfaces: GlbSurface[] = [];
  const clip = clipOption(args);
  const askedRate = numberOption(args, 'rate');
  // --prefetch MB: CPU bytes the next time point may take when fetched ahead (0: none)
  const prefetchMb = numberOption(args, 'prefetch');
  if (prefetchMb !== undefined && !(prefetchMb >= 0)) throw new UsageError('--prefetch must be MB, 0 or more');
  const noPrefetch = prefetchMb === 0;
  const prefetchBytes = prefetchMb === undefined ? undefined : prefetchMb * 2 ** 20;
  const deadlineMs = deadlineOption(args);
  const opts = {
    level: numberOption(args, 'level'),
    budget,
    deadlineMs,
    channel: numberOption(args, 'channel'),
    ranges: stringOption(args, 'ranges'),
    maxStreamBytes: streamBudgetOption(args),
    view: viewOption(args),
    clip,
  };
  let axis: StoreTimeAxis | null;
  try {
    axis = await storeTimeAxis(input, { deadlineMs });
  } catch (e) {
    if (e instanceof StoreError || e instanceof ZfpFormatError) throw new InputError(e.message, { cause: e });
    throw e;
  }
  const count = axis?.count ?? 1;
  const times = sliceIndices(slice, count);
  const shown = formatTimeSlice(slice);
  if (times.length === 0)
    throw new UsageError(
      `--time ${timeText}: ${input} has ${count} time point${count === 1 ? '' : 's'}${axis ? '' : ' (no t axis)'} (0..${count - 1}); the slice ${shown} selects none of them`,
    );
  ctx.log(`${input}: time points ${times.join(', ')} of ${count} (--time ${shown})`);
  // each time point's store says the same notes: each is logged once
  const logged = new Set<string>();
  const quiet = {
    log(m: string) {
      if (m.startsWith('note: ') && logged.has(m)) return;
      logged.add(m);
      ctx.log(m);
    },
  };
  const device = await ctx.gpu();
  // one device for every time point; everything made on it is metered, so what a time point leaves behind is seen
  const { gpu, meter } = meteredGpu(device);
  const records: (SurfaceRecord & TimeOfRecord & { bytesFetched?: number; msToSurface?: number })[] = [];
  const timePoints: Record<string, unknown>[] = [];
  let first: { volume: OpenedInput; dims: unknown; blockGrid: unknown; memoryBudget: number } | undefined;
  let seriesRate = askedRate;
  // the next time point's chunks are fetched while this one's surfaces are computed (series/prefetch.ts)
  const source = storeForLocation(input);
  const prefetch = new SeriesPrefetch();
  const prefetched: (PrefetchState | null)[] = [];
  try {
    for (const [i, t] of times.entries()) {
      const opened = performance.now();
      const prepared = await prefetch.take(t, source);
      prefetched[i] = prepared?.state ?? null;
      const volume = await openInputSurface(quiet, gpu, input, { ...opts, rate: seriesRate, time: t, prepared: prepared ?? undefined });
      const when: TimeOfRecord = { time: t };
      const value = axis ? timeValueOf(axis, t) : null;
      if (value !== null) when.timeValue = value;
      if (axis?.unit) when.timeUnit = axis.unit;
      const label = `t ${t}${value === null ? '' : ` (${value}${axis?.unit ? ` ${axis.unit}` : ''})`}: `;
      let storeRecord: ReturnType<NonNullable<OpenedInput['store']>> | undefined;
      try {
        ctx.log(`${label}${volume.how}`);
        // a store of lossless chunks: the rate chosen from the data at the first time point is the series' rate
        if (seriesRate === undefined && volume.store?.().source) seriesRate = volume.rate;
        const next = times[i + 1];
        const ahead = volume.ahead;
        if (next !== undefined && ahead && !noPrefetch)
          prefetch.start(source, {
            time: next,
            open: (metered) =>
              openStore(metered, input, {
                ...(deadlineMs === undefined ? {} : { retry: { deadlineMs } }),
                rate: seriesRate,
                time: next,
                channel: opts.channel,
                ...(opts.ranges === undefined ? {} : { ranges: { store: storeForLocation(opts.ranges), name: opts.ranges } }),
              }),
            wanted: async (needsAt) => {
              await ahead.planned;
              return ahead.wanted(needsAt);
            },
            levels: ahead.levels,
            ...(prefetchBytes === undefined ? {} : { capacityBytes: prefetchBytes }),
          });
        const made = await surfacesOf(ctx, volume, isovalues, {
          input,
          clip,
          ply: plyPrefix === undefined ? undefined : (isoValue) => `${plyPrefix}-t${t}-iso${isoValue}.ply`,
          glb: glbPath === undefined ? undefined : { surfaces: glbSurfaces, name: (isoValue) => `t ${t} iso ${isoValue}` },
          logPrefix: label,
        });
        const ms = performance.now() - opened;
        storeRecord = volume.store?.();
        for (const r of made) records.push({ ...r, ...when, bytesFetched: storeRecord?.bytesFetched, msToSurface: ms });
        if (!first)
          first = { volume, dims: volume.iso.info.dims, blockGrid: volume.iso.info.blockGrid, memoryBudget: volume.iso.memoryBudget };
        timePoints.push({
          ...when,
          ...(prefetched[i] ? { prefetched: prefetched[i] } : {}),
          rate: volume.rate,
          valueRange: volume.iso.info.valueRange,
          msToSurfaces: ms,
          notes: volume.notes,
          ...(storeRecord ? { store: storeRecord } : {}),
        });
      } finally {
        volume.destroy();
      }
      timePoints[timePoints.length - 1].gpuBytesAfter = meter.bytes;
    }
  } finally {
    prefetch.cancel();
  }
  if (glbPath !== undefined && first) await writeGlb(ctx, glbPath, glbSurfaces, input, first.volume.placement);
  const v = first!.volume;
  const result = {
    input,
    how: v.how,
    rate: v.rate,
    rateError: v.rateChoice ? rateErrorRecord(v.rateChoice) : null,
    dims: first!.dims,
    blockGrid: first!.blockGrid,
    voxelSize: v.placement.voxelSize,
    origin: v.placement.origin,
    unit: v.placement.unit,
    time: { selection: shown, count, indices: times, ...(axis?.unit ? { unit: axis.unit } : {}) },
    ...(glbPath !== undefined ? { glb: glbPath } : {}),
    notes: v.notes,
    adapter: describeAdapter(gpu.adapter),
    gpuPeakBytes: meter.peak,
    memoryBudgetBytes: first!.memoryBudget,
    isosurfaces: records,
    timePoints,
  };
  failIfAnyFailed(records, first!.memoryBudget, result);
  return result;
}
