// The page's store view (`?store=URL`, a dropped or picked `.zarr` folder):
// opens a Zarr store of zfp chunks (src/store/) and hands it to the stream
// controller, which fetches only the chunks the surface needs into GPU pools
// of compressed chunks: the coarsest level first, then refinement level by
// level, each finer level replacing the coarser surface once every chunk it
// needs is resident. Each level the controller shows is installed in the
// session as the volume on screen (store-surface.ts), so the isovalue
// slider, the statistics and the exports work as for any volume, and
// scrubbing goes through the controller (newest wins, stale requests
// aborted). A progress line (level, chunks done / needed, bytes) and a panel
// (levels, network, memory). Errors name the store; the current surface stays.
import type { AsyncReadable } from '@zarrita/storage';
import type { GpuContext } from '../../gpu/device.ts';
import type { ChunkFetcher } from '../../store/fetch/chunk-fetcher.ts';
import { sessionRanges } from '../../store/learnt-ranges.ts';
import { isZipStoreName, storeZipBytes, ZipStore } from '../../store/zarr/zip-store.ts';
import { storeRateChooser } from '../../store/rate.ts';
import { StoreSession } from '../../store/session.ts';
import type { ChunkStreamController } from '../../store/pinned-level.ts';
import type { StreamProgress } from '../../store/stream-controller.ts';
import { StoreError } from '../../store/zarr/errors.ts';
import { HttpStore } from '../../store/zarr/http-store.ts';
import type { ZfpStore } from '../../store/zarr/open-store.ts';
import type { MeteredStore } from '../../store/zarr/stores.ts';
import type { CameraState } from '../../render/camera.ts';
import { cameraForBox, cameraFromView, fitBox0, sceneRadiusOf, type Viewport } from '../../store/view/camera.ts';
import { estimateFixedBytes } from '../../store/level-state.ts';
import { type LevelValues, readLevelValues } from '../../store/level-values.ts';
import { DEFAULT_TOLERANCE_PX, type ViewSpec, ViewStream } from '../../store/view/view-stream.ts';
import type { ChunkViewStream } from '../../store/view/view-surface.ts';
import { type ShownCutOfPage, StoreCutIsosurface } from './store-cut.ts';
import { chooseIsovalue } from '../iso-choice.ts';
import type { LoadedVolume } from '../loading/loader.ts';
import { renderStorePanel, type StoreChoice, type StorePageState } from './store-panel.ts';
import { type ShownLevel, StoreLevelIsosurface } from './store-surface.ts';

export type { StorePageState };

export interface StoreViewDeps {
  /** The device to stream to (the page's current one). */
  gpu: () => GpuContext;
  /** Puts a level on screen as the current volume (Session.install); `first` for the store's first level. */
  install(volume: LoadedVolume, level: number | undefined, first: boolean): void;
  /** The isovalue to open at when the page's link gives one (used as given, even outside a provisional range). */
  linkIso(valueRange: [number, number]): number | undefined;
  /** The volume installed reaches further than its value range said: the slider spans `range` (Session.widenValueRange). */
  widenValueRange(volume: LoadedVolume, range: [number, number]): void;
  budgetBytes(): number;
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
function learntOf(store: ZfpStore, source: AsyncReadable) {
  let id = sourceIds.get(source);
  if (id === undefined) sourceIds.set(source, (id = ++sourceCount));
  const values = store.source
    ? `${store.source.rate}|${store.source.time.index}|${store.source.channel.index}`
    : String(store.levels[0].layout.rate);
  return sessionRanges(
    `${id}|${values}`,
    store.levels.map((l) => l.layout.chunkGrid),
  );
}
const sourceIds = new WeakMap<AsyncReadable, number>();
let sourceCount = 0;

/** Store notes a user should act on (the rest only go to the panel). */
const WARNING_NOTE = /unfinished|is not used|cannot be shown/;

const mib = (b: number) => `${(b / 2 ** 20).toFixed(2)} MiB`;

export type { StoreChoice };

interface OpenStore {
  url: string;
  source: AsyncReadable;
  choice: StoreChoice;
  ranges: { store: AsyncReadable; name: string } | undefined;
  /** The opened store, its fetcher, stream and counters (src/store/session.ts); the next four are its parts. */
  session: StoreSession;
  store: ZfpStore;
  metered: MeteredStore;
  fetcher: ChunkFetcher;
  /** Level by level (StreamController), or refined by the view (ViewStream). */
  controller: ChunkStreamController | ChunkViewStream;
  /** Refined by the view: its tolerance and tint; null when level by level. */
  cut: { tolerancePx: number; tint: boolean } | null;
  /** A camera change waits this timer (throttled re-planning), and unsubscribes with this. */
  replanTimer: ReturnType<typeof setTimeout> | null;
  detachCamera: () => void;
  valueRange: [number, number];
  /** The coarsest level read whole at open when the store gives no value range (level-values.ts): the slider's range and profile until finer ones are known. */
  coarse: LevelValues | null;
  state: StorePageState;
  current: StoreLevelIsosurface | StoreCutIsosurface | null;
  /** The volume installed on the page for `current`. */
  installed: LoadedVolume | null;
  /** Refinements started and not yet ended (the isovalue changed meanwhile). */
  running: number;
  lastProgress: StreamProgress | null;
  /** The isovalue asked for last. */
  iso: number;
}

export class StoreView {
  #gen = 0;
  #open: OpenStore | null = null;
  /** True while this view installs another level of its store (the session then lets the previous one go). */
  #replacing = false;
  /** The isovalue a store opened again another way (panel: rate, time, channel) keeps, over the link's. */
  #keepIso: number | undefined;
  /** The panel's refinement choice, over the link's and the default, for the stores opened from now on. */
  #cutChoice: { cut?: boolean; tolerancePx?: number; tint?: boolean } = {};

  constructor(private readonly d: StoreViewDeps) {}

  /** A store by URL (same origin, or another one with CORS); `rangesUrl`: its per-brick ranges written apart (&ranges=). */
  open(url: string, rangesUrl?: string | null): Promise<void> {
    const ranges = rangesUrl ? { store: new HttpStore(new URL(rangesUrl, location.href).href), name: rangesUrl } : undefined;
    const href = new URL(url, location.href);
    // a zipped store (.ozx): read in place with range requests
    const source = isZipStoreName(href.pathname)
      ? new ZipStore(
          storeZipBytes(new HttpStore(new URL('.', href).href), `/${href.pathname.slice(href.pathname.lastIndexOf('/') + 1)}`, url),
          url,
        )
      : new HttpStore(href.href);
    return this.openStore(source, url, undefined, ranges);
  }

  /**
   * What opens the store on screen again, at the isovalue it was asked for
   * (the page, on a new device after the old one was lost); null when no
   * store is open. Take it before the session lets the store's level go.
   */
  reopener(): { iso: number; open: () => Promise<void> } | null {
    const o = this.#open;
    if (!o) return null;
    return { iso: o.iso, open: () => this.openStore(o.source, o.url, o.choice, o.ranges) };
  }

  /**
   * Another volume is on screen now: the open store stops streaming. Its GPU
   * side is freed here if none of its levels is on screen, else when the
   * session lets that level go (the level's draw data stays valid until then).
   */
  close(): void {
    this.#gen++;
    const o = this.#open;
    this.#open = null;
    if (!o) return;
    this.#stop(o);
    this.#line('');
    this.d.panel.hidden = true;
  }

  /** Stops a store: no more requests; its controller is destroyed unless one of its levels is still on screen. */
  #stop(o: OpenStore): void {
    o.detachCamera();
    if (o.replanTimer !== null) clearTimeout(o.replanTimer);
    o.session.close(o.current !== null);
  }

  /**
   * Any store (a dropped or picked folder: zarr/stores.ts); `url` names it in
   * messages; `choice` (a store of lossless chunks: rate, time point,
   * channel) defaults to the link's. Resolves when the first isovalue's
   * refinement ends.
   */
  async openStore(
    source: AsyncReadable,
    url: string,
    choice: StoreChoice = this.d.linkStoreChoice(),
    ranges?: { store: AsyncReadable; name: string },
  ): Promise<void> {
    const gen = ++this.#gen;
    let cut = null as OpenStore['cut'];
    this.#line(`Opening ${url}…`);
    let session: StoreSession;
    try {
      const asked = { ...this.d.linkCut(), ...this.#cutChoice };
      session = await StoreSession.open(this.d.gpu(), source, url, {
        open: {
          rate: choice.storeRate,
          chooseRate: storeRateChooser(this.d.gpu()),
          time: choice.time,
          channel: choice.channel,
          ranges,
          decodeWorkers: true,
        },
        budgetBytes: this.d.budgetBytes(),
        learnt: (store) => learntOf(store, source),
        // refined by the view (asked for, or level 0 too large to stream whole): each region at the level the camera needs
        view: (store) => {
          if (!(asked.cut ?? this.#levelZeroIsLarge(store))) return null;
          cut = { tolerancePx: asked.tolerancePx ?? DEFAULT_TOLERANCE_PX, tint: asked.tint ?? false };
          return this.#viewSpec(store, cut.tolerancePx, asked.camera);
        },
      });
    } catch (e) {
      // a failed open has let its store go (decode workers, requests)
      if (gen === this.#gen) this.#line('');
      this.d.onError(e instanceof StoreError ? e.message : `${url}: ${(e as Error).message}`);
      return;
    }
    const { store, metered, fetcher: f, stream: controller } = session;
    // no value range in the metadata nor from range arrays: the coarsest level, read whole now, gives one (provisional)
    let coarse: LevelValues | null = null;
    if (!controller.valueRange && gen === this.#gen) {
      this.#line(`${url}: reading level ${controller.coarsest} for the value range…`);
      try {
        coarse = await readLevelValues(store, controller.coarsest);
      } catch {
        // the surface's own path reports a chunk that cannot be read; the range then comes from the first surface
        coarse = null;
      }
    }
    if (gen !== this.#gen) {
      // superseded by another open: this one lets its store go
      session.close();
      return;
    }
    // the previous store (if any) stops here; its level stays on screen until this one's first level replaces it
    const previous = this.#open;
    if (previous) this.#stop(previous);
    const finest = Math.min(this.d.linkLevel() ?? 0, store.levels.length - 1);
    controller.finest = finest;
    const state: StorePageState = {
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
      })),
      retries: 0,
      failedRequests: 0,
      gpu: { pools: 0, surfaces: 0, cache: 0, vertices: 0, total: 0, peak: 0, budget: controller.budgetBytes },
      cut: cut ? { tolerancePx: cut.tolerancePx, tint: cut.tint, levels: [], final: false } : null,
    };
    const shownChoice: StoreChoice = store.source
      ? {
          storeRate: store.source.rate,
          ...(store.source.time.count > 1 ? { time: store.source.time.index } : {}),
          ...(store.source.channel.count > 1 ? { channel: store.source.channel.index } : {}),
        }
      : {};
    this.d.setStoreChoice(shownChoice);
    const o: OpenStore = {
      url,
      source,
      choice: shownChoice,
      ranges,
      session,
      store,
      metered,
      fetcher: f,
      controller,
      cut,
      replanTimer: null,
      detachCamera: () => {},
      valueRange: controller.valueRange ?? coarse?.valueRange ?? [0, 0],
      coarse,
      state,
      current: null,
      installed: null,
      running: 0,
      lastProgress: null,
      iso: NaN,
    };
    this.#open = o;
    if (controller.valueRange) state.valueRange = { lo: o.valueRange[0], hi: o.valueRange[1], provisional: false, from: 'the store' };
    else if (coarse?.valueRange)
      state.valueRange = {
        lo: o.valueRange[0],
        hi: o.valueRange[1],
        provisional: true,
        from: `level ${coarse.level} (${coarse.dims.join('×')}) read whole at open, ${mib(coarse.bytes)}`,
      };
    this.d.setCut(cut ? { cut: true, tolerancePx: cut.tolerancePx, ...(cut.tint ? { tint: true } : {}) } : {});
    if (cut) o.detachCamera = this.d.onCameraChange(() => this.#scheduleReplan(o));
    // what the store is and how it is read goes to the panel; what a user should act on is also a (dismissable) notice
    state.notes = [...store.notes];
    for (const note of store.notes) if (WARNING_NOTE.test(note)) this.d.onNotice(`${url}: ${note}`);
    // chunks counted once (a bit per chunk of each level: session.ts)
    session.fetched.onNew((level, bytes) => {
      state.chunksFetched++;
      state.levels[level].chunksFetched++;
      state.levels[level].chunkBytesFetched += bytes;
    });
    controller.onProgress((p) => this.#progress(o, p));
    if (controller instanceof ViewStream) controller.onShown((s) => this.#shownCut(o, s));
    else {
      controller.onShown((s) => this.#shown(o, s));
      // a chunk that failed has cooled down: the same isovalue again (the coarser surface stayed meanwhile)
      controller.onRetry((value) => {
        if (this.#open === o && value === o.iso) void this.#refine(o, value);
      });
    }
    controller.onError((e) => this.d.onError(e.message));
    this.#publish(o);

    // The isovalue: the link's, else Otsu over the finest known chunk ranges. A
    // store without range arrays shows its coarsest level (fetched whole) first,
    // whose block ranges then give the value range and the choice.
    // (a store without ranges has no value range before its coarsest level is read: the link's isovalue waits for it)
    // the link's isovalue (or the one kept over a reopen) is used as given, even outside a provisional range
    const linkIso = (range: [number, number]) => {
      const kept = this.#keepIso;
      this.#keepIso = undefined;
      return kept !== undefined && Number.isFinite(kept) ? kept : this.d.linkIso(range);
    };
    let iso = controller.valueRange || coarse?.valueRange ? linkIso(o.valueRange) : undefined;
    if (iso === undefined && coarse?.valueRange) iso = chooseIsovalue(coarse.blockRanges, o.valueRange);
    if (iso === undefined) {
      let ranges: Float32Array | null = null;
      for (let L = finest; L < store.levels.length && !ranges; L++) ranges = controller.chunkRanges(L);
      if (!ranges) {
        controller.finest = controller.coarsest;
        await this.#refine(o, 0);
        if (gen !== this.#gen) return;
        controller.finest = finest;
        ranges = controller.chunkRanges(controller.coarsest);
        o.valueRange = controller.valueRange ?? o.valueRange;
        if (o.current) (o.current.info as { valueRange: [number, number] }).valueRange = o.valueRange;
        iso = linkIso(o.valueRange);
      }
      iso ??= ranges ? chooseIsovalue(ranges, o.valueRange) : (o.valueRange[0] + o.valueRange[1]) / 2;
    }
    await this.#refine(o, iso);
  }

  /** One isovalue's refinement, with `done` and the line kept current. */
  async #refine(o: OpenStore, iso: number): Promise<void> {
    if (this.#open !== o) return; // stopped: its level on screen only waits to be replaced
    o.iso = iso;
    o.running++;
    o.state.done = false;
    this.#publish(o);
    try {
      await o.controller.setIsovalue(iso);
    } finally {
      o.running--;
    }
    if (this.#open !== o || o.running > 0) return;
    o.state.done = true;
    if (o.cut) {
      this.#cutLine(o);
      this.#publish(o);
      return;
    }
    const shown = o.state.shownLevel;
    const p = o.lastProgress;
    if (p?.phase === 'stopped' && p.reason)
      o.state.reason = p.retryInMs !== undefined ? `${p.reason} (trying again in ${Math.ceil(p.retryInMs / 1000)} s)` : p.reason;
    if (shown === null) this.#line(`${o.url}: nothing shown${o.state.reason ? `; ${o.state.reason}` : ''}`);
    else if (shown === 0) this.#line(`${o.url}: level 0 (full resolution), ${mib(o.metered.meter.bytes)} fetched`);
    else this.#line(`${o.url}: level ${shown} shown${o.state.reason ? `; ${o.state.reason}` : ''}`);
    this.#publish(o);
  }

  #progress(o: OpenStore, p: StreamProgress): void {
    if (this.#open !== o) return;
    o.lastProgress = p;
    if (p.phase === 'fetching')
      this.#line(`${o.url}: level ${p.level}, ${p.chunksDone} / ${p.chunksNeeded} chunks, ${mib(o.metered.meter.bytes)}`);
    else if (p.phase === 'computing') this.#line(`${o.url}: level ${p.level}, computing the surface…`);
    this.#publish(o);
  }

  /** The controller shows a level: the same level again updates the panel; another one is installed as the volume on screen. */
  #shown(o: OpenStore, s: ShownLevel): void {
    if (this.#open !== o) return;
    if (o.state.reason && o.state.reason !== `the link asks for level ${o.controller.finest}`) o.state.reason = null;
    if (o.current instanceof StoreLevelIsosurface && o.current.level === s.level) {
      o.current.showAgain(s);
    } else {
      const first = o.current === null;
      const iso = new StoreLevelIsosurface(
        o.controller as ChunkStreamController,
        s,
        o.valueRange,
        (value) => this.#refine(o, value),
        () => {
          // the session let this level go: another level of the store replaces it, or the store is done
          if (this.#replacing && this.#open === o) return;
          if (this.#open === o) this.close();
          o.controller.destroy();
        },
        (bytes) => {
          if (bytes === o.controller.budgetBytes) return;
          // the whole stream's budget from now on; a refinement that stopped for room tries again
          o.controller.budgetBytes = bytes;
          o.state.gpu.budget = bytes;
          if (this.#open === o && Number.isFinite(o.iso)) void this.#refine(o, o.iso);
        },
      );
      const k = 2 ** s.level;
      const name = `${o.url} level ${s.level}`;
      // the level where its metadata puts it: a coarse voxel at the centre of the finer ones it averages
      const volume = storeVolume(
        o,
        name,
        s.level,
        k,
        iso,
        s.iso,
        s.stats,
        o.controller.chunkRanges(s.level) ?? o.coarse?.blockRanges ?? null,
      );
      // installed at once: the controller frees the coarser surface right after this returns
      this.#replacing = !first;
      try {
        this.d.install(volume, s.level, first);
      } finally {
        this.#replacing = false;
      }
      o.current = iso;
      o.installed = volume;
      o.state.shownLevels.push(s.level);
    }
    o.state.shownLevel = s.level;
    this.#widen(o);
    this.#publish(o);
  }

  /**
   * A provisional value range (the coarsest level's, read at open) widened
   * by the brick ranges the stream has learnt since (either engine, as
   * bricks arrive). Final once every brick of level 0 is known.
   */
  #widen(o: OpenStore): void {
    const vr = o.state.valueRange;
    if (this.#open !== o || !vr?.provisional) return;
    const c = o.controller;
    // both engines learn brick ranges as bricks arrive (learnt-ranges.ts)
    const learnt = c.learnt.valueRange();
    const bricks = o.store.levels.reduce((a, _, L) => a + c.learnt.knownCount(L), 0);
    const complete = c.learnt.knownCount(0) === o.store.levels[0].chunkCount;
    if (!learnt) return;
    const lo = Math.min(vr.lo, learnt[0]);
    const hi = Math.max(vr.hi, learnt[1]);
    if (lo === vr.lo && hi === vr.hi && !complete) return;
    o.valueRange = [lo, hi];
    o.state.valueRange = {
      lo,
      hi,
      provisional: !complete,
      from: complete
        ? `every brick of level 0, as decoded at rate ${o.store.levels[0].layout.rate}`
        : `${vr.from.split('; ')[0]}; widened by ${bricks} bricks learnt as they arrived`,
    };
    if (o.installed) this.d.widenValueRange(o.installed, o.valueRange);
    this.#publish(o);
  }

  #publish(o: OpenStore): void {
    const st = o.state;
    const g = o.controller.gpuBytes;
    Object.assign(st, {
      bytesFetched: o.metered.meter.bytes,
      // a store of lossless chunks: what came over for the bricks, not the bricks' values (as the CLI's record)
      chunkBytesFetched: o.store.source ? o.metered.meter.bytes - o.store.metadataBytes : o.fetcher.counters.bytesFetched,
      requests: o.metered.meter.requests,
    });
    st.gpu = { ...g, peak: Math.max(st.gpu.peak, g.total), budget: o.controller.budgetBytes };
    st.retries = o.store.retries.retries;
    st.failedRequests = o.store.retries.failed;
    renderStorePanel(
      this.d.panel,
      o.store,
      st,
      o.fetcher.counters,
      (next) => {
        if (this.#open !== o) return;
        this.#keepIso = Number.isFinite(o.iso) ? o.iso : undefined;
        void this.openStore(o.source, o.url, { ...o.choice, ...next }, o.ranges);
      },
      (next) => this.#changeCut(o, next),
    );
    this.d.publish({ ...st, levels: st.levels.map((l) => ({ ...l })), shownLevels: [...st.shownLevels] });
  }

  /**
   * Refine by the view when a store's level 0 is large: its chunks, at what
   * the GPU keeps per resident chunk, would take more than a quarter of the
   * budget (level by level it would stop coarse everywhere). Smaller stores
   * go level by level to full resolution, as before; the panel and the
   * link's cut= choose either way.
   */
  #levelZeroIsLarge(store: ZfpStore): boolean {
    const L = store.levels.find((l) => !l.unusable);
    if (!L) return false;
    // a resident chunk: its slot and the surface's per-block state (the 64 KiB of a pool's scratch are not per chunk)
    const perChunk = L.layout.chunkBytes + estimateFixedBytes(L.layout, 1) - (64 << 10);
    return L.chunkCount * perChunk > this.d.budgetBytes() / 4;
  }

  /** The view spec of the page's camera now, or (before the store's first surface) the link's camera or Fit of level 0. */
  #viewSpec(store: ZfpStore, tolerancePx: number, linkCamera?: CameraState, current = false): ViewSpec {
    const { state, viewport } = this.d.camera();
    const vp = viewport.width > 0 && viewport.height > 0 ? viewport : { width: 1280, height: 800 };
    const level0 = fitBox0(store.levels[0].layout, 0);
    const sceneRadius = sceneRadiusOf(level0, store.voxelSize);
    const camState = current ? state : linkCamera;
    const camera = camState ? cameraFromView(camState, vp, sceneRadius) : cameraForBox(level0, store.voxelSize, vp);
    return { camera, tolerancePx };
  }

  /** The camera moved: the cut is planned again at most every 150 ms (newest wins; the stream aborts what is no longer needed). */
  #scheduleReplan(o: OpenStore): void {
    if (o.replanTimer !== null || this.#open !== o || !o.cut) return;
    o.replanTimer = setTimeout(() => {
      o.replanTimer = null;
      if (this.#open !== o || !o.cut || !o.current) return;
      void this.#refineView(o);
    }, 150);
  }

  /** The current isovalue refined for the page's camera now. */
  async #refineView(o: OpenStore): Promise<void> {
    const stream = o.controller as ChunkViewStream;
    o.running++;
    o.state.done = false;
    this.#publish(o);
    try {
      await stream.setView(this.#viewSpec(o.store, o.cut!.tolerancePx, undefined, true));
    } finally {
      o.running--;
    }
    if (this.#open !== o || o.running > 0) return;
    o.state.done = true;
    this.#cutLine(o);
    this.#publish(o);
  }

  /** The line once a view's refinement ended: what is on screen, or why it stopped. */
  #cutLine(o: OpenStore): void {
    const c = o.state.cut;
    const p = o.lastProgress;
    if (p?.phase === 'stopped' && p.reason) o.state.reason = p.reason;
    const on = c?.levels.filter((l) => l.drawn > 0).map((l) => `level ${l.level}: ${l.drawn}`) ?? [];
    this.#line(
      `${o.url}: ${on.length > 0 ? `chunks on screen ${on.join(', ')}` : 'no surface in view'}, ${mib(o.metered.meter.bytes)} fetched` +
        (o.state.reason ? `; ${o.state.reason}` : ''),
    );
  }

  /** The panel's refinement controls: by view or level by level (the store opens again), the tolerance, the tint. */
  #changeCut(o: OpenStore, next: { cut?: boolean; tolerancePx?: number; tint?: boolean }): void {
    if (this.#open !== o) return;
    this.#cutChoice = { ...this.#cutChoice, ...next };
    if (next.cut !== undefined && next.cut !== (o.cut !== null)) {
      this.#keepIso = Number.isFinite(o.iso) ? o.iso : undefined;
      void this.openStore(o.source, o.url, o.choice, o.ranges);
      return;
    }
    if (!o.cut) return;
    if (next.tint !== undefined) {
      o.cut.tint = next.tint;
      if (o.current instanceof StoreCutIsosurface) o.current.tint = next.tint;
      this.d.requestFrame();
    }
    if (next.tolerancePx !== undefined && next.tolerancePx > 0) {
      o.cut.tolerancePx = next.tolerancePx;
      void this.#refineView(o);
    }
    this.d.setCut({ cut: true, tolerancePx: o.cut.tolerancePx, ...(o.cut.tint ? { tint: true } : {}) });
    if (o.state.cut) Object.assign(o.state.cut, { tolerancePx: o.cut.tolerancePx, tint: o.cut.tint });
    this.#publish(o);
  }

  /** The view stream shows a step of its cut: the first becomes the volume on screen (level 0's dims), later ones update it. */
  #shownCut(o: OpenStore, s: ShownCutOfPage): void {
    if (this.#open !== o) return;
    const finest = s.levels[0]?.level ?? s.step;
    const levels = o.store.levels.map((_, L) => {
      const l = s.levels.find((x) => x.level === L);
      return { level: L, drawn: l ? l.drawn.length : 0, regions: s.leaves[L]?.length ?? 0, triangles: l?.stats.triangles ?? 0 };
    });
    o.state.cut = { tolerancePx: o.cut!.tolerancePx, tint: o.cut!.tint, levels, final: s.final };
    if (o.state.reason && !o.state.reason.startsWith('the link')) o.state.reason = null;
    if (o.current instanceof StoreCutIsosurface) {
      o.current.showAgain(s);
    } else if (s.levels.length > 0) {
      const stream = o.controller as ChunkViewStream;
      const iso = new StoreCutIsosurface(
        stream,
        s,
        o.valueRange,
        (value) => this.#refine(o, value),
        () => {
          if (this.#open === o) this.close();
          stream.destroy();
        },
        (bytes) => {
          if (bytes === stream.budgetBytes) return;
          stream.budgetBytes = bytes;
          o.state.gpu.budget = bytes;
          if (this.#open === o && Number.isFinite(o.iso)) void this.#refine(o, o.iso);
        },
      );
      iso.tint = o.cut!.tint;
      // level 0's volume: the pieces of coarser levels are drawn at their own scale and place (store-cut.ts)
      const volume = storeVolume(
        o,
        o.url,
        0,
        1,
        iso,
        s.iso,
        iso.stats,
        o.controller.chunkRanges(o.controller.coarsest) ?? o.coarse?.blockRanges ?? null,
      );
      this.d.install(volume, undefined, true); // no level= in the link: the view decides
      o.current = iso;
      o.installed = volume;
      // the page's camera now (the link's, or Fit of the volume): plan for it
      this.#scheduleReplan(o);
    }
    if (o.state.shownLevel !== finest) o.state.shownLevels.push(finest);
    o.state.shownLevel = finest;
    this.d.requestFrame();
    this.#publish(o);
    // the ranges of the bricks this step read are recorded once their readback arrives
    void (o.controller as ChunkViewStream).learnSettled().then(() => this.#widen(o));
  }

  #line(text: string): void {
    this.d.line.hidden = text === '';
    this.d.line.textContent = text;
  }
}

/**
 * A store shown as the session's volume: level `level`'s dims at `scale` times
 * the store's voxel size, placed by its OME translation; the stream owns the
 * pools (the volume's own stream is nothing to destroy).
 */
function storeVolume(
  o: OpenStore,
  name: string,
  level: number,
  scale: number,
  iso: LoadedVolume['iso'],
  initialIso: number,
  firstStats: LoadedVolume['firstStats'],
  ranges: Float32Array | null,
): LoadedVolume {
  const lv = o.store.levels[level];
  const off = o.store.levelOffsets[level] ?? [0, 0, 0];
  return {
    opened: {
      stream: { destroy() {} },
      name,
      fileName: name,
      kind: 'zfp',
      dims: [...lv.layout.dims],
      sourceDtype: 'float32',
      sourceBytes: lv.storedBytes,
      compressedBytes: lv.storedBytes,
      rate: lv.layout.rate,
      compressedHere: false,
      spacing: [o.store.voxelSize[0] * scale, o.store.voxelSize[1] * scale, o.store.voxelSize[2] * scale],
      origin: [off[0] / scale, off[1] / scale, off[2] / scale],
      notes: [],
    },
    iso,
    ranges: ranges ?? new Float32Array(0),
    initialIso,
    firstStats,
    loadMs: 0,
  };
}
