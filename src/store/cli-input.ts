// The CLI's store input (`extract` / `bench` STORE --level L, or refined by
// --view-box / --view): a store URL, folder or zip opened as a StoreSession
// (session.ts, as the page opens it), read as one surface (stream-surface.ts):
// at level L only, each isovalue fetches the chunks its surface needs (8
// requests in flight) into the level's GPU pool of compressed chunks; by a
// view, every level the cut uses. The record says how much came over.
import type { Clip } from '../core/clip.ts';
import { existsSync, mkdirSync, readFileSync, rmSync, statSync, writeFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import type { GpuContext } from '../gpu/device.ts';
import { defaultMemoryBudget } from '../isosurface/budget.ts';
import { storeRateChooser } from './rate.ts';
import { type StoreRecord, StoreSession } from './session.ts';
import { type ViewRequest, viewSpecFor } from './view/view-request.ts';
import type { ViewSpec } from './stream/store-stream.ts';
import type { ChunkStoreStream } from './gpu-port.ts';
import type { PreparedTime } from './series/prefetch.ts';
import { StoreStreamSurface } from './stream-surface.ts';
import { StoreError } from './zarr/errors.ts';
import { isStoreUrl, storeForLocation } from './zarr/node-store.ts';
import { rangesSidecarFiles } from './zarr/ranges-sidecar-files.ts';
import type { StoreTimeAxis, ZfpStore } from './zarr/store.ts';
import { openStore } from './zarr/open-store.ts';
import { isZipStoreName } from './zarr/zip-store.ts';

/** --level names a level the store does not have (a wrong command line, not a data failure). */
export class NoSuchLevelError extends Error {
  constructor(message: string) {
    super(message);
    this.name = 'NoSuchLevelError';
  }
}

/** A URL, or a folder with Zarr metadata at its root (v3 zarr.json, v2 .zgroup or .zarray). */
export function isStoreInput(input: string): boolean {
  return isStoreUrl(input) || isZipStoreName(input) || ['zarr.json', '.zgroup', '.zarray'].some((f) => existsSync(join(input, f)));
}

export type { StoreRecord };

export interface StoreInput {
  surface: StoreStreamSurface;
  how: string;
  rate: number;
  notes: string[];
  fileName: string;
  /** The physical size of one voxel of the positions read (the pinned level's, or level 0's for a view), and its unit (OME). */
  voxelSize: [number, number, number];
  unit: string | null;
  /** The store's figures so far. */
  record(): StoreRecord;
  /**
   * A store of lossless chunks: writes the brick ranges known now (learnt
   * as bricks arrived, or a level's once resident whole) as a ranges sidecar
   * folder (--save-ranges); absent for a zfp store.
   */
  saveRanges?(dir: string): Promise<{ known: number; bricks: number }>;
  /** What the next time point of a series would want (series/prefetch.ts), once this one's stream has planned. */
  ahead: SeriesAhead;
}

/** The plan of the time point open now, as a series' next one is fetched ahead from it. */
export interface SeriesAhead {
  /** Resolves once the stream has its isovalue (its first plan made). */
  planned: Promise<void>;
  wanted: ChunkStoreStream['wantedAhead'];
  /** The levels its plans may read (those of their range arrays read ahead). */
  levels: number[];
}

/** The session's stream seen as a series' plan ahead. */
function aheadOf(session: StoreSession): SeriesAhead {
  const { stream } = session;
  // its first progress (or a step shown: a plan with nothing to fetch) says the plan is made
  const planned = new Promise<void>((resolve) => {
    const offs = [stream.onProgress(done), stream.onShown(done)];
    function done() {
      for (const off of offs) off();
      resolve();
    }
  });
  return {
    planned,
    wanted: (needsAt) => stream.wantedAhead(needsAt),
    levels: session.store.levels.map((_, L) => L).filter((L) => L >= stream.finest),
  };
}

export interface StoreInputOptions {
  /** The level to stream (default 0). */
  level?: number;
  /** The GPU memory of the whole stream (everything it holds); by default the pipeline's default budget. */
  budget?: number;
  /** How long one request is tried (default 30 s; retrying-store.ts). */
  deadlineMs?: number;
  /** Stores of lossless chunks: the GPU's zfp rate (default 8); time point and channel (default 0). */
  rate?: number;
  time?: number;
  channel?: number;
  /** Per-brick ranges written apart (--ranges-only), a URL or folder. */
  ranges?: string;
  /** Refine by this view instead of streaming one level (--view-box, --view): a mixed-level surface (src/store/view/). */
  view?: ViewRequest;
  /** Cuts the surfaces open: chunks it removes whole are neither fetched nor drawn. */
  clip?: Clip;
  /** Surfaces of block caches only, no triangles (`render --draw rays`): the budget holds bricks, not vertices. */
  cacheOnly?: boolean;
  /** This time point fetched ahead (extract --time): taken over, store and all. */
  prepared?: PreparedTime;
}

export async function openStoreInput(gpu: GpuContext, input: string, opts: StoreInputOptions): Promise<StoreInput> {
  const L = opts.level ?? 0;
  const budgetBytes = opts.budget ?? defaultMemoryBudget(gpu.device.limits);
  let view: ViewSpec | undefined;
  const session = await StoreSession.open(gpu, storeForLocation(input), input, {
    cacheOnly: opts.cacheOnly,
    prepared: opts.prepared,
    open: {
      ...(opts.deadlineMs === undefined ? {} : { retry: { deadlineMs: opts.deadlineMs } }),
      rate: opts.rate,
      chooseRate: storeRateChooser(gpu),
      time: opts.time,
      channel: opts.channel,
      ...(opts.ranges === undefined ? {} : { ranges: { store: storeForLocation(opts.ranges), name: opts.ranges } }),
    },
    budget: budgetBytes,
    // checked before any stream is made: a level that does not exist or cannot be drawn, a view that does not fit the store
    view: (store) => {
      if (!Number.isInteger(L) || L < 0 || L >= store.levels.length)
        throw new NoSuchLevelError(`${input}: --level ${opts.level} does not exist (levels 0 to ${store.levels.length - 1})`);
      const unusable = store.levels[L].unusable;
      if (unusable) throw new StoreError('layout', `${input}: --level ${L}: ${unusable}`);
      if (!opts.view) return null;
      try {
        view = viewSpecFor(
          opts.view,
          store.levels.map((l) => l.layout),
          store.voxelSize,
        );
      } catch (e) {
        throw new StoreError('layout', `${input}: ${(e as Error).message}`);
      }
      return view;
    },
    setup: (stream) => {
      stream.retryFailed = false; // the CLI reports a chunk that failed (after the store's own retries)
      stream.skirts = opts.view?.skirts ?? true;
      stream.snapshots = false; // nothing is drawn while it refines: the surfaces are read once it ends
      if (opts.clip) stream.setClip(opts.clip);
    },
  });
  const { store } = session;
  if (!store.source && opts.ranges !== undefined)
    store.notes.push(`--ranges is for stores of lossless chunks; this store's chunks are zfp, with their own ranges or none`);
  if (!store.source && opts.rate !== undefined && opts.rate !== store.levels[0].layout.rate)
    store.notes.push(
      `--rate ${opts.rate} is for stores of lossless chunks; this store's chunks are zfp at rate ${store.levels[0].layout.rate}, used as they are`,
    );
  if (view) return viewInput(input, session, view);
  const { stream } = session;
  const lv = store.levels[L];
  const surface = new StoreStreamSurface(stream, L);
  const kind = store.source
    ? `${store.source.format} store of ${store.source.dtype} (${store.source.codecs.join(' + ') || 'uncompressed'}), level ${L} of ${store.levels.length} (${lv.layout.dims.join('x')}, ${lv.layout.chunkEdge}^3 bricks compressed on the GPU at rate ${lv.layout.rate})`
    : `Zarr store, level ${L} of ${store.levels.length} (${lv.layout.dims.join('x')}, ${lv.layout.chunkEdge}^3 chunks, rate ${lv.layout.rate})`;
  const how = `${kind}, ` + `streamed: the chunks each surface needs, within ${(budgetBytes / 2 ** 20).toFixed(0)} MiB of GPU memory`;
  return {
    surface,
    how,
    rate: lv.layout.rate,
    notes: store.notes,
    fileName: `${input} level ${L}`,
    voxelSize: store.voxelSize.map((s, a) => s * store.levelScales[L][a]) as [number, number, number],
    unit: store.unit,
    record: () => session.record(L, L, L),
    ahead: aheadOf(session),
    // levels with range arrays: those; the others: what was learnt as bricks arrived, a level learnt in part included
    ...(store.source
      ? {
          saveRanges: async (dir: string) =>
            writeSidecar(store, dir, (l) => (store.levels[l].rangesPath ? stream.chunkRanges(l) : stream.learnt.level(l))),
        }
      : {}),
  };
}

/**
 * The store's t axis (how many time points, where the OME metadata put
 * them), or null when it has none: its metadata only are read (no chunk, no
 * rate chosen). Rejects with StoreError as opening does.
 */
export async function storeTimeAxis(input: string, opts: { deadlineMs?: number }): Promise<StoreTimeAxis | null> {
  const store = await openStore(
    storeForLocation(input),
    input,
    opts.deadlineMs === undefined ? {} : { retry: { deadlineMs: opts.deadlineMs } },
  );
  store.close?.();
  return store.time ?? null;
}

/** Writes a ranges sidecar folder (ranges-sidecar-files.ts); an existing folder is replaced only when it is a ranges sidecar. */
function writeSidecar(store: ZfpStore, dir: string, ranges: (level: number) => Float32Array | null): { known: number; bricks: number } {
  const sidecar = rangesSidecarFiles(store, ranges);
  if (existsSync(dir)) {
    let isSidecar = false;
    try {
      isSidecar = statSync(dir).isDirectory() && readFileSync(join(dir, 'zarr.json'), 'utf8').includes('"zfpzarr_ranges"');
    } catch {
      // not a folder with a zarr.json
    }
    if (!isSidecar) throw new StoreError('layout', `${dir}: exists and is not a ranges sidecar; give a new folder to --save-ranges`);
    rmSync(dir, { recursive: true, force: true });
  }
  for (const [path, bytes] of sidecar.files) {
    mkdirSync(dirname(join(dir, path)), { recursive: true });
    writeFileSync(join(dir, path), bytes);
  }
  return { known: sidecar.known, bricks: sidecar.bricks };
}

/**
 * A store refined by a view (--view-box, --view): every level the cut uses,
 * each region at the level the view needs; the record's `level` is the
 * finest level drawn, `chunks` the distinct chunks put at any level.
 */
function viewInput(input: string, session: StoreSession, view: ViewSpec): StoreInput {
  const { store, stream } = session;
  const surface = new StoreStreamSurface(stream, null);
  const lv0 = store.levels[0];
  const how =
    `Zarr store of ${store.levels.length} levels (level 0 ${lv0.layout.dims.join('x')}, ${lv0.layout.chunkEdge}^3 chunks, rate ${lv0.layout.rate}), ` +
    `refined by the view (each region at the level whose voxels project to at most ${view.tolerancePx} px), within ${(session.budgetBytes / 2 ** 20).toFixed(0)} MiB of GPU memory`;
  // levels with range arrays (a sidecar given): those; the others: what the stream learnt as bricks arrived
  const saveRanges = async (dir: string) => {
    await stream.learnSettled();
    return writeSidecar(store, dir, (l) => (store.levels[l].rangesPath ? stream.chunkRanges(l) : stream.learnt.level(l)));
  };
  return {
    surface,
    how,
    rate: lv0.layout.rate,
    notes: store.notes,
    fileName: `${input} (view)`,
    voxelSize: [...store.voxelSize],
    unit: store.unit,
    record: () => session.record(Math.min(...(stream.shown?.levels.map((l) => l.level) ?? [0])), 0),
    ahead: aheadOf(session),
    ...(store.source ? { saveRanges } : {}),
  };
}
