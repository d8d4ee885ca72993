// An opened volume (a zfp stream on the GPU) to its Isosurface with a first
// surface computed: what the main page's loader and the neuron page share.
// All or nothing: on any failure or cancel the Isosurface and the stream are
// freed before the error is passed on, so a caller never holds a half-made
// volume.

import type { GpuContext } from '../../gpu/device.ts';
import type { IsosurfaceStats } from '../../isosurface/types.ts';
import { checkValueRange, type OpenedVolume } from '../../volume/open-volume.ts';
import { createIsosurface, type PageIsosurface } from '../engine.ts';
import { LoadCancelled } from './read.ts';

/** An opened volume as the page keeps it: the stream is only freed through it (a store level's belongs to the store). */
export type PageVolume = Omit<OpenedVolume, 'stream'> & { stream: { destroy(): void } };

export interface SurfaceVolume {
  opened: PageVolume;
  iso: PageIsosurface;
  /** [min, max] per block (block profile, isovalue choice). */
  ranges: Float32Array;
  initialIso: number;
  firstStats: IsosurfaceStats;
}

export type FirstSurfaceStage = 'ranges' | 'surface';

export interface FirstSurfaceOptions {
  /** Bytes the cache and vertex buffers may take; the pipeline's default when undefined. */
  memoryBudget?: number;
  /** The isovalue of the first surface, once the block ranges are known. */
  chooseIso: (opened: OpenedVolume, iso: PageIsosurface, ranges: Float32Array) => number;
  signal?: AbortSignal;
  onStage?: (stage: FirstSurfaceStage) => void;
}

/** Takes ownership of `opened`: it is part of the result, or freed on failure. Rejects with LoadCancelled when `signal` aborts. */
export async function openFirstSurface(gpu: GpuContext, opened: OpenedVolume, opts: FirstSurfaceOptions): Promise<SurfaceVolume> {
  const { signal } = opts;
  let iso: PageIsosurface | undefined;
  try {
    if (signal?.aborted) throw new LoadCancelled();
    opts.onStage?.('ranges');
    iso = await createIsosurface(gpu, opened.stream, opts.memoryBudget !== undefined ? { memoryBudgetBytes: opts.memoryBudget } : {});
    if (signal?.aborted) throw new LoadCancelled();
    // No finite value (a zfp file of NaN/Inf): refused here, named, before any isovalue is chosen.
    checkValueRange(opened.fileName, iso.info.valueRange);
    const ranges = await iso.readBlockRanges();
    const initialIso = opts.chooseIso(opened, iso, ranges);
    opts.onStage?.('surface');
    const firstStats = await iso.compute(initialIso);
    if (signal?.aborted) throw new LoadCancelled();
    return { opened, iso, ranges, initialIso, firstStats };
  } catch (e) {
    iso?.destroy();
    opened.stream.destroy();
    throw e;
  }
}

/** The message for a failed load: the error's own text when it names the file, else prefixed with it. */
export function loadErrorMessage(what: string, e: unknown): string {
  const text = e instanceof Error ? e.message : String(e);
  return text.includes(what) ? text : `${what}: ${text}`;
}
