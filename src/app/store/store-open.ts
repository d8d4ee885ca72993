// The store view's parts that are not its behaviour: what it needs from the
// page (StoreViewDeps), what it keeps of an open store (OpenStore), the
// panel's state at open, the volume a shown level is installed as, and the
// ranges learnt per opened source for the session.
import type { AsyncReadable } from '@zarrita/storage';
import { HttpStore } from '../../store/zarr/http-store.ts';
import { isZipStoreName, storeZipBytes, ZipStore } from '../../store/zarr/zip-store.ts';
import { residentChunkBytes } from '../../store/level-state.ts';
import { cameraForBox, cameraFromView, fitBox0, sceneRadiusOf } from '../../store/view/camera.ts';
import type { ViewSpec } from '../../store/stream/store-stream.ts';
import type { GpuBudget } from '../../gpu/budget.ts';
import type { GpuContext } from '../../gpu/device.ts';
import { sessionRanges } from '../../store/learnt-ranges.ts';
import type { StoreSession } from '../../store/session.ts';
import type { StreamProgress } from '../../store/stream-port.ts';
import type { ZfpStore } from '../../store/zarr/open-store.ts';
import type { CameraState } from '../../render/camera.ts';
import type { Viewport } from '../../store/view/camera.ts';
import type { LevelValues } from '../../store/level-values.ts';
import type { StoreIsosurface } from './store-isosurface.ts';
import type { LoadedVolume } from '../loading/loader.ts';
import type { StoreChoice, StorePageState } from './store-panel.ts';

export interface StoreViewDeps {
  /** The device to stream to (the page's current one). */
  gpu: () => GpuContext;
  /** The page's one GPU memory budget: every store holds against it. */
  budget: GpuBudget;
  /** CPU bytes a series' next time point may take when fetched ahead (the link's prefetch=MiB; 0: none; default series/prefetch.ts's). */
  prefetchBytes?: number;
  /** Puts a store on screen as the current volume (Session.install), once per opened store. */
  install(volume: LoadedVolume): void;
  /** The store level the link reopens (level by level: the level on screen), or undefined (the view decides). */
  setLevel(level: number | undefined): void;
  /** What the page holds on the GPU against the budget now (the budget control's meter). */
  showGpuBytes(bytes: number): void;
  /** The isovalue to open at when the page's link gives one (used as given, even outside a provisional range). */
  linkIso(valueRange: [number, number]): number | undefined;
  /** The volume installed reaches further than its value range said: the slider spans `range` (Session.widenValueRange). */
  widenValueRange(volume: LoadedVolume, range: [number, number]): void;
  onError(message: string): void;
  onNotice(message: string): void;
  /** The finest level to show (a link's #level=), or undefined for level 0. */
  linkLevel(): number | undefined;
  /** A store of lossless chunks: the link's rate, time point and channel (#rate=, t=, c=). */
  linkStoreChoice(): StoreChoice;
  /** What the link says about the store open now (empty for a zfp store or no store). */
  setStoreChoice(choice: StoreChoice): void;
  /** Where the page tests read the figures (window.zfpisoStore). */
  publish(state: StorePageState): void;
  /** The page's camera now and its canvas in device pixels (a store refined by the view plans its cut from them). */
  camera(): { state: CameraState; viewport: Viewport };
  /** Called after every camera change; returns an unsubscribe function. */
  onCameraChange(listener: () => void): () => void;
  /** The link's refinement (cut=1|0, tol=, tint=) and camera. */
  linkCut(): { cut?: boolean; tolerancePx?: number; tint?: boolean; camera?: CameraState };
  /** What the link says of the refinement of the store open now. */
  setCut(cut: { cut?: boolean; tolerancePx?: number; tint?: boolean }): void;
  requestFrame(): void;
  /**
   * Before the store opens again at another time point (playback, the time
   * slider): what to keep of the page (camera, clip, the voxel size set
   * here, the other surfaces) over what a new volume resets; the function
   * returned puts back the other surfaces once the time point is on screen.
   * Absent: the page's defaults for a new volume.
   */
  keepPage?(voxelSize: readonly number[]): () => Promise<void>;
  line: HTMLElement;
  panel: HTMLElement;
}

/**
 * What was learnt of this store's bricks (at this rate, time point and
 * channel) earlier in the session, whichever engine learnt it. Keyed by the
 * source object the store was opened from (the page opens the same one again
 * for another rate, time point, channel or refinement), not by its name: two
 * dropped folders of one name are two stores.
 */
export function learntOf(store: ZfpStore, source: AsyncReadable) {
  let id = sourceIds.get(source);
  if (id === undefined) sourceIds.set(source, (id = ++sourceCount));
  const values = store.source
    ? `${store.source.rate}|${store.source.time.index}|${store.source.channel.index}`
    : `${store.levels[0].layout.rate}|${store.time?.index ?? 0}`;
  return sessionRanges(
    `${id}|${values}`,
    store.levels.map((l) => l.layout.chunkGrid),
  );
}
const sourceIds = new WeakMap<AsyncReadable, number>();
let sourceCount = 0;

/** Store notes a user should act on (the rest only go to the panel). */
export const WARNING_NOTE = /unfinished|is not used|cannot be shown/;

export const mib = (b: number) => `${(b / 2 ** 20).toFixed(2)} MiB`;

export interface OpenStore {
  url: string;
  source: AsyncReadable;
  choice: StoreChoice;
  ranges: { store: AsyncReadable; name: string } | undefined;
  /** The opened store, its fetcher, stream and counters (src/store/session.ts). */
  session: StoreSession;
  store: ZfpStore;
  /** Refined by the view: its tolerance and tint; null when level by level. */
  cut: { tolerancePx: number; tint: boolean } | null;
  /** Another store is opening: this one keeps only what it draws, and nothing moves it (StoreSession.suspend). */
  suspended: boolean;
  /** A camera change waits this timer (throttled re-planning), and unsubscribes with this. */
  replanTimer: ReturnType<typeof setTimeout> | null;
  detachCamera: () => void;
  valueRange: [number, number];
  /** The coarsest level read whole at open when the store gives no value range (level-values.ts): the slider's range and profile until finer ones are known. */
  coarse: LevelValues | null;
  state: StorePageState;
  current: StoreIsosurface | null;
  /** The volume installed on the page for `current`. */
  installed: LoadedVolume | null;
  /** Refinements started and not yet ended (the isovalue changed meanwhile). */
  running: number;
  lastProgress: StreamProgress | null;
  /** The refinement asked for last is where the rays hit (a cut for rays): the line says so. */
  guided: boolean;
  /** The isovalue asked for last. */
  iso: number;
  /** Drawn only once its first refinement has ended (playback: the time point before stays drawn until then). */
  whole: boolean;
  /** Another time point of the store on screen: the page keeps its camera, clip, voxel size and surfaces (StoreViewDeps.keepPage). */
  keepPage: boolean;
  /** The page's other surfaces put back once it was installed (keepPage). */
  restoring: Promise<void>;
}

/** The panel's figures when a store opens: nothing fetched or shown yet; the value range the store or its coarsest level gave. */
export function initialPageState(
  url: string,
  store: ZfpStore,
  stream: { budgetBytes: number; valueRange: [number, number] | null },
  finest: number,
  cut: OpenStore['cut'],
  coarse: LevelValues | null,
): StorePageState {
  const range = stream.valueRange ?? coarse?.valueRange;
  return {
    url,
    shownLevel: null,
    shownLevels: [],
    done: false,
    bytesFetched: 0,
    chunkBytesFetched: 0,
    requests: 0,
    chunksFetched: 0,
    reason: finest > 0 ? `the link asks for level ${finest}` : null,
    levels: store.levels.map((l) => ({
      level: l.index,
      dims: l.layout.dims,
      chunks: l.chunkCount,
      chunkBytes: l.layout.chunkBytes,
      storedBytes: l.storedBytes,
      chunksFetched: 0,
      chunkBytesFetched: 0,
      chunksShown: 0,
    })),
    retries: 0,
    failedRequests: 0,
    gpu: { pools: 0, surfaces: 0, cache: 0, vertices: 0, store: 0, total: 0, peak: 0, budget: stream.budgetBytes },
    parts: [],
    steps: [],
    stepsShown: 0,
    cut: cut ? { tolerancePx: cut.tolerancePx, tint: cut.tint, levels: [], final: false } : null,
    notes: [...store.notes],
    ...(range
      ? {
          valueRange: stream.valueRange
            ? { lo: range[0], hi: range[1], provisional: false, from: 'the store' }
            : {
                lo: range[0],
                hi: range[1],
                provisional: true,
                from: `level ${coarse!.level} (${coarse!.dims.join('×')}) read whole at open, ${mib(coarse!.bytes)}`,
              },
        }
      : {}),
  };
}

/**
 * The panel's network and GPU figures now, from the session's counters (the
 * same the CLI's record reads): what this store holds (pools, surfaces, of
 * these cache and vertices: `store`), and against the page's one budget what
 * the page holds (`total`, a store being replaced included) and the most it
 * held since the budget was last set (`peak`: every allocation counted).
 */
export function updatePageFigures(st: StorePageState, session: StoreSession): void {
  const { store, metered, fetcher, stream, budget } = session;
  const g = stream.gpuBytes;
  st.bytesFetched = metered.meter.bytes;
  // a store of lossless chunks: what came over for the bricks, not the bricks' values (as the CLI's record)
  st.chunkBytesFetched = store.source ? metered.meter.bytes - store.metadataBytes : fetcher.counters.bytesFetched;
  st.requests = metered.meter.requests;
  st.gpu = {
    pools: g.pools,
    surfaces: g.surfaces,
    cache: g.cache,
    vertices: g.vertices,
    store: g.total,
    total: budget.heldBytes,
    peak: budget.meter.peak,
    budget: budget.bytes,
  };
  st.clippedChunks = stream.clippedChunks;
  const queue = store.decodeQueue?.();
  if (queue) st.decodeQueue = queue;
  st.retries = store.retries.retries;
  st.failedRequests = store.retries.failed;
  const shown = stream.shown?.levels ?? [];
  for (const l of st.levels) {
    const s = shown.find((x) => x.level === l.level);
    l.chunksShown = s ? s.drawn.length + s.ghosts.length : 0;
  }
}

/**
 * What the link says of the store open now: the time point when it has
 * several (any store: a zfp store's t axis too), and for a store of lossless
 * chunks its rate and channel.
 */
export function storeChoiceOf(store: ZfpStore): StoreChoice {
  const time = store.time ?? store.source?.time;
  return {
    ...(store.source ? { storeRate: store.source.rate } : {}),
    ...(time && time.count > 1 ? { time: time.index } : {}),
    ...(store.source && store.source.channel.count > 1 ? { channel: store.source.channel.index } : {}),
  };
}

/** The store behind a URL (same origin, or another one with CORS); a zipped store (.ozx) is read in place with range requests. */
export function storeSourceOfUrl(url: string): AsyncReadable {
  const href = new URL(url, location.href);
  return isZipStoreName(href.pathname)
    ? new ZipStore(
        storeZipBytes(new HttpStore(new URL('.', href).href), `/${href.pathname.slice(href.pathname.lastIndexOf('/') + 1)}`, url),
        url,
      )
    : new HttpStore(href.href);
}

/**
 * A store shown as the session's volume: level 0's dims at the store's voxel
 * size (the pieces of coarser levels are drawn at their own scale and place);
 * the stream owns the pools (the volume's own stream is nothing to destroy).
 */
export function storeVolume(
  o: OpenStore,
  iso: LoadedVolume['iso'],
  initialIso: number,
  firstStats: LoadedVolume['firstStats'],
  ranges: Float32Array | null,
): LoadedVolume {
  const lv = o.store.levels[0];
  return {
    opened: {
      stream: { destroy() {} },
      name: o.url,
      fileName: o.url,
      kind: 'zfp',
      dims: [...lv.layout.dims],
      sourceDtype: 'float32',
      sourceBytes: lv.storedBytes,
      compressedBytes: lv.storedBytes,
      rate: lv.layout.rate,
      compressedHere: false,
      spacing: [...o.store.voxelSize],
      origin: [...(o.store.levelOffsets[0] ?? [0, 0, 0])],
      notes: [],
    },
    iso,
    ranges: ranges ?? new Float32Array(0),
    initialIso,
    firstStats,
    loadMs: 0,
  };
}

/**
 * Refine by the view when a store's level 0 is large: its chunks, at what
 * the GPU keeps per resident chunk, would take more than a quarter of the
 * budget (level by level it would stop coarse everywhere). Smaller stores
 * go level by level to full resolution, as before; the panel and the
 * link's cut= choose either way.
 */
export function levelZeroIsLarge(store: ZfpStore, budgetBytes: number): boolean {
  const L = store.levels.find((l) => !l.unusable);
  if (!L) return false;
  // a resident chunk: its slot and the surface's per-block state (the 64 KiB of a pool's scratch are not per chunk)
  return L.chunkCount * residentChunkBytes(L.layout) > budgetBytes / 4;
}

/** The view spec of the page's camera now (`current`), or (before the store's first surface) the link's camera or Fit of level 0. */
export function pageViewSpec(
  page: { state: CameraState; viewport: Viewport },
  store: ZfpStore,
  tolerancePx: number,
  linkCamera?: CameraState,
  current = false,
): ViewSpec {
  const { state, viewport } = page;
  const vp = viewport.width > 0 && viewport.height > 0 ? viewport : { width: 1280, height: 800 };
  const level0 = fitBox0(store.levels[0].layout, 0);
  const sceneRadius = sceneRadiusOf(level0, store.voxelSize);
  const camState = current ? state : linkCamera;
  const camera = camState ? cameraFromView(camState, vp, sceneRadius) : cameraForBox(level0, store.voxelSize, vp);
  return { camera, tolerancePx };
}
