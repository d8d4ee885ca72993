// The input of `extract` and `bench` as one surface: a volume file (zfp,
// raw, NRRD, TIFF stack, or `default`) opened as the page opens it
// (src/volume/open-volume.ts) with the isosurface pipeline over its stream,
// or a Zarr store (URL or folder) streamed at --level L (src/store/): each
// isovalue fetches only the chunks its surface needs. A file or store that
// cannot be read is an InputError (exit status 1), a wrong option a
// UsageError (2); everything made is freed on failure.
import { readFileSync } from 'node:fs';
import { basename } from 'node:path';
import type { GpuContext } from '../gpu/device.ts';
import { Isosurface } from '../isosurface/isosurface.ts';
import { isStoreInput, NoSuchLevelError, openStoreInput, type SeriesAhead, type StoreRecord } from '../store/cli-input.ts';
import type { PreparedTime } from '../store/series/prefetch.ts';
import type { ViewRequest } from '../store/view/view-request.ts';
import { type Clip, parseClipBox } from '../core/clip.ts';
import type { CutChunkRecord } from '../store/stream-surface.ts';
import { StoreError } from '../store/zarr/errors.ts';
import {
  checkValueRange,
  describeOpenedVolume,
  isDefaultVolume,
  openDefaultVolume,
  openVolumeBytes,
  VolumeFileError,
} from '../volume/open-volume.ts';
import { ZfpFormatError } from '../zfp/format.ts';
import { describeRateChoice, type RateChoice } from '../zfp/rate-choice.ts';
import { InputError, UsageError } from './command.ts';

/**
 * What `extract` and `bench` use of a surface: an Isosurface, or a store's
 * stream (StoreStreamSurface: one level pinned, or the view's cut of several
 * levels, so no one packed mesh; its positions come in the level's or
 * level-0 voxels, with the cut).
 */
export type InputSurface = Pick<Isosurface, 'info' | 'compute' | 'resetCache' | 'memoryBudget' | 'destroy'> &
  (
    | Pick<Isosurface, 'readMesh'>
    | {
        /** The mesh at `iso` (one of those drawn together; default the last computed). */
        readPositions(iso?: number): Promise<{ positions: Float32Array; indices: Uint32Array }>;
        cutRecord(iso?: number): Promise<CutChunkRecord[] | undefined>;
        /** Isovalues drawn together in one refinement (StoreStreamSurface.together). */
        together(isos: readonly number[]): void;
      }
  );

export interface OpenedInput {
  iso: InputSurface;
  how: string;
  rate: number;
  /** Volumes compressed here: how the rate was found and its error (the record's `rateError`). */
  rateChoice?: RateChoice;
  notes: string[];
  /** Where the positions read lie: voxel (i, j, k) at ((i, j, k) + origin) * voxelSize, in `unit` (null: unknown). */
  placement: { voxelSize: [number, number, number]; origin: [number, number, number]; unit: string | null };
  /** A store's figures (bytes fetched, chunks), for the JSON record. */
  store?: () => StoreRecord;
  /** A store of lossless chunks: writes the brick ranges known now as a ranges sidecar (--save-ranges). */
  saveRanges?: (dir: string) => Promise<{ known: number; bricks: number }>;
  /** A store: its plan, as a series' next time point is fetched ahead from it (extract --time). */
  ahead?: SeriesAhead;
  destroy(): void;
}

/**
 * --level and --deadline are for stores; `budget`: the pipeline's memory
 * budget (for a store: everything it holds on the GPU).
 */
export async function openInputSurface(
  ctx: { log(m: string): void },
  gpu: GpuContext,
  path: string,
  opts: {
    rate?: number;
    level?: number;
    budget?: number;
    deadlineMs?: number;
    maxStreamBytes?: number;
    time?: number;
    channel?: number;
    ranges?: string;
    view?: ViewRequest;
    /** Cuts the surfaces open (the caller clips the meshes); a store leaves out the chunks it removes whole. */
    clip?: Clip;
    /** Surfaces of block caches only, no triangles (drawn by rays: `render`). */
    cacheOnly?: boolean;
    /** A store's time point fetched ahead (extract --time): taken over. */
    prepared?: PreparedTime;
  },
): Promise<OpenedInput> {
  if (isStoreInput(path)) {
    try {
      const s = await openStoreInput(gpu, path, opts);
      for (const note of s.notes) ctx.log(`note: ${note}`);
      return {
        iso: s.surface,
        how: s.how,
        rate: s.rate,
        notes: s.notes,
        placement: { voxelSize: s.voxelSize, origin: [0, 0, 0], unit: s.unit },
        store: s.record,
        ...(s.saveRanges ? { saveRanges: s.saveRanges } : {}),
        ahead: s.ahead,
        destroy: () => s.surface.destroy(),
      };
    } catch (e) {
      if (e instanceof NoSuchLevelError) throw new UsageError(e.message);
      if (e instanceof StoreError || e instanceof ZfpFormatError) throw new InputError(e.message, { cause: e });
      throw e;
    }
  }
  if (opts.level !== undefined) throw new UsageError('--level is for a Zarr store (a URL or a folder with zarr.json)');
  if (opts.view !== undefined) throw new UsageError('--view and --view-box are for a Zarr store (a URL or a folder with zarr.json)');
  if (opts.time !== undefined || opts.channel !== undefined || opts.ranges !== undefined)
    throw new UsageError('--time, --channel and --ranges are for a Zarr store of lossless chunks (a URL or a folder with zarr.json)');
  if (opts.deadlineMs !== undefined) throw new UsageError('--deadline is for a Zarr store (a URL or a folder with zarr.json)');
  const { rate } = opts;
  if (rate !== undefined && !(rate > 0)) throw new UsageError('--rate must be positive');
  // `default`: the page's built-in volume, same field, same rate, same stream.
  let bytes: Uint8Array | undefined;
  if (!isDefaultVolume(path)) {
    try {
      bytes = new Uint8Array(readFileSync(path));
    } catch (e) {
      throw new InputError(`cannot read ${path}: ${(e as Error).message}`);
    }
  }
  let v;
  try {
    v = bytes
      ? await openVolumeBytes(gpu.device, bytes, basename(path), { rate, reader: 'command', maxStreamBytes: opts.maxStreamBytes })
      : await openDefaultVolume(gpu.device, { ...(rate === undefined ? {} : { rate }), maxStreamBytes: opts.maxStreamBytes });
  } catch (e) {
    if (e instanceof VolumeFileError || e instanceof ZfpFormatError) throw new InputError(e.message, { cause: e });
    throw e;
  }
  for (const note of v.notes) ctx.log(`note: ${note}`);
  if (v.rateChoice) ctx.log(`note: ${v.fileName}: ${describeRateChoice(v.rateChoice)}`);
  let iso: Isosurface | undefined;
  try {
    iso = await Isosurface.create(gpu, v.stream, {
      ...(opts.budget === undefined ? {} : { memoryBudgetBytes: opts.budget }),
      ...(opts.cacheOnly ? { cacheOnly: true } : {}),
    });
    checkValueRange(v.fileName, iso.info.valueRange);
    checkClip(v.fileName, opts.clip, iso.info.dims);
  } catch (e) {
    iso?.destroy();
    v.stream.destroy();
    if (e instanceof VolumeFileError) throw new InputError(e.message, { cause: e });
    throw e;
  }
  const stream = v.stream;
  const made = iso;
  return {
    iso: made,
    how: describeOpenedVolume(v),
    rate: v.rate,
    ...(v.rateChoice ? { rateChoice: v.rateChoice } : {}),
    notes: v.notes,
    placement: { voxelSize: v.spacing ?? [1, 1, 1], origin: v.origin ?? [0, 0, 0], unit: null },
    destroy: () => {
      made.destroy();
      stream.destroy();
    },
  };
}

/** A clip box that holds no cell of the volume is refused (it would cut everything away). */
function checkClip(name: string, clip: Clip | undefined, dims: readonly number[]): void {
  if (!clip?.box) return;
  const why = parseClipBox(clip.box.join(','), dims);
  if (typeof why === 'string') throw new VolumeFileError(`${name}: --clip ${clip.box.join(',')}: ${why}`);
}
