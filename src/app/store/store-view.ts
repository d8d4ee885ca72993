// The page's store view (`?store=URL`, a dropped or picked folder or .ozx):
// opens the store as a StoreSession (src/store/session.ts: level by level,
// or refined by the view when asked or when level 0 is large) and draws the
// step its stream shows, whichever planner made it, as one volume on screen
// (store-isosurface.ts), so the slider, statistics and exports work as for
// any volume; a progress line and a panel (levels, network, memory). Every
// store holds against the page's one GPU budget: the store on screen gives
// back all but what it draws before another one (or another rate, time point
// or channel) allocates, and ends once the new one is drawn. Errors name the
// store; the current surface stays. Its parts that are not behaviour:
// store-open.ts.
import type { Clip } from '../../core/clip.ts';
import type { AsyncReadable } from '@zarrita/storage';
import { type LevelValues, readLevelValues } from '../../store/level-values.ts';
import { storeRateChooser } from '../../store/rate.ts';
import { StoreSession } from '../../store/session.ts';
import type { StreamProgress } from '../../store/stream-port.ts';
import { DEFAULT_TOLERANCE_PX } from '../../store/stream/store-stream.ts';
import { StoreError } from '../../store/zarr/errors.ts';
import { HttpStore } from '../../store/zarr/http-store.ts';
import { chooseIsovalue } from '../iso-choice.ts';
import {
  initialPageState,
  learntOf,
  levelZeroIsLarge,
  mib,
  type OpenStore,
  pageViewSpec,
  storeChoiceOf,
  storeSourceOfUrl,
  type StoreViewDeps,
  storeVolume,
  updatePageFigures,
  WARNING_NOTE,
} from './store-open.ts';
import { StoreIsosurface, type ShownStep } from './store-isosurface.ts';
import { renderStorePanel, type StoreChoice, type StorePageState } from './store-panel.ts';
import { Playback } from './playback.ts';
import { type PrefetchState, type PreparedTime, SeriesPrefetch } from '../../store/series/prefetch.ts';
import { openStore as openZarrStore } from '../../store/zarr/open-store.ts';
import type { StoreTimeAxis } from '../../store/zarr/store.ts';

export type { StoreViewDeps };

export type { StorePageState };

export type { StoreChoice };

/** Why a store is refined: a new isovalue, a new view (the camera moved), or what the rays saw (StoreStream.setSeen; null: the view's cut again). */
type RefineHow = 'iso' | 'view' | { seen: Uint32Array | null };

export class StoreView {
  #gen = 0;
  #open: OpenStore | null = null;
  /** The isovalue a store opened again another way (panel: rate, time, channel, refinement) keeps, over the link's. */
  #keepIso: number | undefined;
  /** The panel's refinement choice, over the link's and the default, for the stores opened from now on. */
  #cutChoice: { cut?: boolean; tolerancePx?: number; tint?: boolean } = {};
  /** The page's clip (setClip). */
  #clip: Clip | undefined;
  /** Whether the page draws the clip's caps (setCaps). */
  #caps = false;
  /** An isovalue the slider asked for while the store on screen was suspended (another time point opening): the new one takes it. */
  #askedIso: number | undefined;
  /** Refinements' ends waited on (whenIdle). */
  #idle: (() => void)[] = [];
  /** The playback of a store's time points (its block in the Store section). */
  readonly playback: Playback;
  /** The next time point played, fetched ahead while the one before is computed and on screen (series/prefetch.ts). */
  readonly #prefetch = new SeriesPrefetch();
  /** The time point asked for after the one opening (playback; -1: the one after it, a series just opened; null: none). */
  #next: number | null = null;
  /** What was fetched ahead for the time point on screen (taken over by its session), or null. */
  #prefetched: PrefetchState | null = null;

  constructor(private readonly d: StoreViewDeps) {
    this.playback = new Playback({
      time: () => this.time,
      showTime: (t, next) => this.showTime(t, next),
      prefetch: () => ({ ahead: this.#prefetch.state, shown: this.#prefetched }),
      changed: () => {
        if (this.#open) this.#publish(this.#open);
      },
    });
    this.#prefetch.onChange(() => this.playback.prefetchChanged());
    // a new limit: the stream gives back what it must at once (its own listener); its refinement for the new limit,
    // asked for here once the streams have shed (a microtask later), is the one the page waits for
    d.budget.onChange(() =>
      queueMicrotask(() => {
        const o = this.#open;
        if (!o) return;
        this.#publish(o);
        if (Number.isFinite(o.iso)) void this.#refine(o, o.iso);
      }),
    );
  }

  /** A store by URL (same origin, or another one with CORS); `rangesUrl`: its per-brick ranges written apart (&ranges=). */
  open(url: string, rangesUrl?: string | null): Promise<void> {
    const ranges = rangesUrl ? { store: new HttpStore(new URL(rangesUrl, location.href).href), name: rangesUrl } : undefined;
    return this.openStore(storeSourceOfUrl(url), url, undefined, ranges);
  }

  /**
   * What opens the store on screen again, at the isovalue it was asked for
   * (the page, on a new device after the old one was lost); null when no
   * store is open. Take it before the session lets the store go.
   */
  reopener(): { iso: number; open: () => Promise<void> } | null {
    const o = this.#open;
    if (!o) return null;
    return { iso: o.iso, open: () => this.openStore(o.source, o.url, o.choice, o.ranges) };
  }

  /** The time axis of the store open now (null: none, or no store). */
  get time(): StoreTimeAxis | null {
    return this.#open?.store.time ?? null;
  }

  /**
   * Shows time point `t` of the store open now: the store opens again there
   * through the one reopen path (the isovalue, the refinement, and with the
   * page's keepPage its camera, clip, voxel size and surfaces kept), drawn
   * only once its refinement has ended (the time point before stays drawn
   * until then). True once it is on screen and every refinement asked
   * meanwhile (a new isovalue) has ended; false when it was not shown (no
   * store, no such time point, the open failed or another store opened).
   * `next`: the time point asked for after this one (playback): it is
   * fetched ahead once this one's refinement has started, within the
   * prefetch bound; what was fetched ahead for `t` is taken over here.
   */
  async showTime(t: number, next: number | null = null): Promise<boolean> {
    const o = this.#open;
    const axis = o?.store.time;
    if (!o || !axis || !Number.isInteger(t) || t < 0 || t >= axis.count) return false;
    this.#next = next !== null && Number.isInteger(next) && next >= 0 && next < axis.count && next !== t ? next : null;
    // the time point on screen first ends what was asked of it (a new isovalue): the next is asked for once it is whole
    await this.whenIdle();
    if (this.#open !== o) return false;
    if (axis.index === t && o.current) {
      this.#ahead(o);
      return true;
    }
    this.#keepIso = Number.isFinite(o.iso) ? o.iso : undefined;
    const prepared = await this.#prefetch.take(t, o.source);
    if (this.#open !== o) {
      prepared?.fetcher.cancelAll();
      prepared?.store.close?.();
      return false;
    }
    await this.openStore(o.source, o.url, { ...o.choice, time: t }, o.ranges, { whole: true, keepPage: true, prepared });
    const n = this.#open;
    if (!n || n === o || n.store.time?.index !== t || !n.current) return false;
    await n.restoring;
    await this.whenIdle();
    return this.#open === n && n.current !== null;
  }

  /** Resolves once the store open now has no refinement running (at once when none is). */
  whenIdle(): Promise<void> {
    const o = this.#open;
    if (!o || o.running === 0) return Promise.resolve();
    return new Promise((resolve) => this.#idle.push(resolve));
  }

  /** The page's clip: the store on screen (and those opened later) leave out the chunks it removes whole. */
  setClip(clip: Clip | undefined): void {
    this.#clip = clip;
    const o = this.#open;
    if (!o || sameClip(o.session.stream.clip, clip)) return;
    o.session.stream.setClip(clip);
    // planned again as any other change (the page waits on this refinement)
    if (Number.isFinite(o.iso)) void this.#refine(o, o.iso);
  }

  /** Whether the page draws the clip's caps: the store on screen (and those opened later) fetch the chunks they read. */
  setCaps(on: boolean): void {
    this.#caps = on;
    const o = this.#open;
    if (!o || o.session.stream.caps === on) return;
    o.session.stream.setCaps(on);
    if (o.session.stream.clip && Number.isFinite(o.iso)) void this.#refine(o, o.iso);
  }

  /** Another volume is on screen now: the open store ends (requests, decodes, timers) and gives back its GPU memory. */
  close(): void {
    this.#gen++;
    this.#prefetch.cancel();
    this.#prefetched = null;
    const o = this.#open;
    this.#open = null;
    if (!o) return;
    this.#end(o);
    this.#line('');
    this.d.panel.hidden = true;
    this.playback.storeShown();
    this.#settle();
  }

  /** Ends a store: nothing of it runs from now on, and every byte it held on the GPU is given back. */
  #end(o: OpenStore): void {
    o.detachCamera();
    if (o.replanTimer !== null) clearTimeout(o.replanTimer);
    o.replanTimer = null;
    o.session.close();
  }

  /**
   * Any store (a dropped or picked folder: zarr/stores.ts); `url` names it in
   * messages; `choice` (a store of lossless chunks: rate, time point,
   * channel) defaults to the link's. The store on screen gives back all but
   * what it draws first (it stays drawn until this one's first step is, and
   * goes on if this one fails to open). Resolves when the first isovalue's
   * refinement ends. `how.whole`: the new store is drawn only once that
   * refinement has ended (playback: never a time point half refined);
   * `how.keepPage`: the page keeps its camera, clip, voxel size and surfaces
   * (another time point of the same store).
   */
  async openStore(
    source: AsyncReadable,
    url: string,
    choice: StoreChoice = this.d.linkStoreChoice(),
    ranges?: { store: AsyncReadable; name: string },
    how: { whole?: boolean; keepPage?: boolean; prepared?: PreparedTime | null } = {},
  ): Promise<void> {
    const gen = ++this.#gen;
    // another store (not a time point of this one): nothing fetched ahead is of use; a series' next time point
    // is fetched ahead once this one's refinement starts (as playback asks for each one it shows)
    if (!how.keepPage) {
      this.#prefetch.cancel();
      this.#next = -1;
    }
    this.#prefetched = how.prepared?.state ?? null;
    this.#askedIso = undefined;
    let cut = null as OpenStore['cut'];
    this.#line(`Opening ${url}…`);
    let previous = this.#open;
    if (previous?.current) this.#suspend(previous);
    else if (previous) {
      // nothing of it on screen: it ends now
      this.#open = null;
      this.#end(previous);
      previous = null;
    }
    let session: StoreSession;
    try {
      const asked = { ...this.d.linkCut(), ...this.#cutChoice };
      session = await StoreSession.open(this.d.gpu(), source, url, {
        prepared: how.prepared ?? undefined,
        open: {
          rate: choice.storeRate,
          chooseRate: storeRateChooser(this.d.gpu()),
          time: choice.time,
          channel: choice.channel,
          ranges,
          decodeWorkers: true,
        },
        budget: this.d.budget,
        learnt: (store) => learntOf(store, source),
        // refined by the view (asked for, or level 0 too large to stream whole): each region at the level the camera needs
        view: (store) => {
          if (!(asked.cut ?? levelZeroIsLarge(store, this.d.budget.bytes))) return null;
          cut = { tolerancePx: asked.tolerancePx ?? DEFAULT_TOLERANCE_PX, tint: asked.tint ?? false };
          return pageViewSpec(this.d.camera(), store, cut.tolerancePx, asked.camera);
        },
      });
    } catch (e) {
      // a failed open has let its store go (decode workers, requests); the store on screen goes on
      if (gen === this.#gen) {
        this.#line('');
        if (previous && this.#open === previous) this.#resume(previous);
      }
      this.d.onError(e instanceof StoreError ? e.message : `${url}: ${(e as Error).message}`);
      return;
    }
    const { store, stream } = session;
    // no value range in the metadata nor from range arrays: the coarsest level, read whole now, gives one (provisional)
    let coarse: LevelValues | null = null;
    if (!stream.valueRange && gen === this.#gen) {
      this.#line(`${url}: reading level ${stream.coarsest} for the value range…`);
      try {
        coarse = await readLevelValues(store, stream.coarsest);
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
    // the previous store stays drawn (its copies only) until this one's first step replaces it
    const finest = Math.min(this.d.linkLevel() ?? 0, store.levels.length - 1);
    stream.finest = finest;
    const state = initialPageState(url, store, stream, finest, cut, coarse);
    const shownChoice = storeChoiceOf(store);
    this.d.setStoreChoice(shownChoice);
    const o: OpenStore = {
      url,
      source,
      choice: shownChoice,
      ranges,
      session,
      store,
      cut,
      suspended: false,
      replanTimer: null,
      detachCamera: () => {},
      valueRange: stream.valueRange ?? coarse?.valueRange ?? [0, 0],
      coarse,
      state,
      current: null,
      installed: null,
      running: 0,
      lastProgress: null,
      guided: false,
      iso: Number.NaN,
      whole: how.whole ?? false,
      keepPage: how.keepPage ?? false,
      restoring: Promise.resolve(),
    };
    this.#open = o;
    this.d.setCut(cut ? { cut: true, tolerancePx: cut.tolerancePx, ...(cut.tint ? { tint: true } : {}) } : {});
    if (cut) o.detachCamera = this.d.onCameraChange(() => this.#scheduleReplan(o));
    // what the store is and how it is read goes to the panel (state.notes); what a user should act on is also a (dismissable) notice
    for (const note of store.notes) if (WARNING_NOTE.test(note)) this.d.onNotice(`${url}: ${note}`);
    // chunks counted once (a bit per chunk of each level: session.ts)
    session.fetched.onNew((level, bytes) => {
      state.chunksFetched++;
      state.levels[level].chunksFetched++;
      state.levels[level].chunkBytesFetched += bytes;
    });
    // fetched ahead (a time point played): counted as the session's own
    for (let L = 0; L < store.levels.length; L++) {
      state.chunksFetched += session.fetched.chunks(L);
      state.levels[L].chunksFetched += session.fetched.chunks(L);
      state.levels[L].chunkBytesFetched += session.fetched.bytes(L);
    }
    // a chunk that failed is tried again by the stream once it has cooled down (the coarser surface stays meanwhile)
    stream.onProgress((p) => this.#progress(o, p));
    // what the stream refines on its own (a retry, a new budget, the rays reading its caches again) is the page's refinement too
    stream.refineAgain = () => void this.#refine(o, o.iso);
    stream.onShown((s) => this.#shown(o, s));
    stream.onError((e) => this.d.onError(e.message));
    stream.setClip(this.#clip);
    stream.setCaps(this.#caps);
    this.#publish(o);

    // The isovalue: the link's (or the one kept over a reopen) as given, even outside a provisional range; else
    // Otsu over the finest known ranges (a store without any: its coarsest level shown first gives them).
    const linkIso = (range: [number, number]) => {
      // the slider moved while this store opened (the one on screen suspended) is newest
      const kept = this.#askedIso ?? this.#keepIso;
      this.#keepIso = undefined;
      this.#askedIso = undefined;
      return kept !== undefined && Number.isFinite(kept) ? kept : this.d.linkIso(range);
    };
    let iso = stream.valueRange || coarse?.valueRange ? linkIso(o.valueRange) : undefined;
    if (iso === undefined && coarse?.valueRange) iso = chooseIsovalue(coarse.blockRanges, o.valueRange);
    if (iso === undefined) {
      let known: Float32Array | null = null;
      for (let L = finest; L < store.levels.length && !known; L++) known = stream.chunkRanges(L);
      if (!known) {
        stream.finest = stream.coarsest;
        await this.#refine(o, 0);
        if (gen !== this.#gen) return;
        stream.finest = finest;
        known = stream.chunkRanges(stream.coarsest);
        o.valueRange = stream.valueRange ?? o.valueRange;
        if (o.current) (o.current.info as { valueRange: [number, number] }).valueRange = o.valueRange;
        iso = linkIso(o.valueRange);
      }
      iso ??= known ? chooseIsovalue(known, o.valueRange) : (o.valueRange[0] + o.valueRange[1]) / 2;
    }
    await this.#refine(o, iso);
  }

  /** The store on screen while another opens: it stops and keeps only what it draws (StoreSession.suspend); the slider and camera do not move it. */
  #suspend(o: OpenStore): void {
    o.suspended = true;
    o.detachCamera();
    o.detachCamera = () => {};
    if (o.replanTimer !== null) clearTimeout(o.replanTimer);
    o.replanTimer = null;
    o.session.suspend();
  }

  /** A suspended store goes on (the store meant to replace it did not open). */
  #resume(o: OpenStore): void {
    o.suspended = false;
    if (o.cut) o.detachCamera = this.d.onCameraChange(() => this.#scheduleReplan(o));
    if (Number.isFinite(o.iso)) void this.#refine(o, o.iso);
  }

  /**
   * One isovalue's refinement (for the view now), with `done` and the line
   * kept current; `others`: the page's other surfaces, drawn with it (default:
   * those drawn until now). `how`: a new isovalue, a new view (the camera
   * moved), or what the rays saw (a cut for rays; null: the view's cut again).
   */
  async #refine(o: OpenStore, iso: number, how: RefineHow = 'iso', others?: readonly number[]): Promise<void> {
    // suspended while another store (time point) opens: the slider's value goes to that one
    if (o.suspended && how === 'iso' && this.#open !== null && Number.isFinite(iso)) this.#askedIso = iso;
    if (this.#open !== o || o.suspended) return; // ended, or suspended while another store opens
    o.iso = iso;
    o.guided = typeof how === 'object' && how.seen !== null;
    o.running++;
    o.state.done = false;
    o.state.shownLevels = o.state.shownLevel === null ? [] : [o.state.shownLevel];
    this.#publish(o);
    try {
      const { stream } = o.session;
      const refined =
        how === 'iso'
          ? stream.setIsovalue(iso, others)
          : how === 'view'
            ? stream.setView(pageViewSpec(this.d.camera(), o.store, o.cut!.tolerancePx, undefined, true))
            : stream.setSeen(how.seen);
      // the stream has its isovalue and view now: the next time point played is planned from them
      this.#ahead(o);
      await refined;
    } finally {
      o.running--;
    }
    // drawn only when whole (playback): the refinement ended, so the step the stream shows now is drawn (it stopped short: where it stopped)
    if (this.#open === o && o.whole && !o.current && o.running === 0) {
      o.whole = false;
      const shown = o.session.stream.shown as ShownStep | null;
      if (shown) this.#shown(o, shown);
    }
    if (this.#open !== o || o.running > 0) {
      this.#settle();
      return;
    }
    o.state.done = true;
    this.#endLine(o);
    this.#publish(o);
    this.#settle();
  }

  /**
   * Fetches the next time point played ahead (#next), from the plan of the
   * store on screen at its isovalue and view with that time point's ranges,
   * within the prefetch bound (the link's prefetch=MiB; 0: none).
   */
  #ahead(o: OpenStore): void {
    const axis = o.store.time;
    // a series just opened: the time point after the one shown
    if (this.#next === -1) this.#next = axis && axis.index + 1 < axis.count ? axis.index + 1 : null;
    const t = this.#next;
    const bound = this.d.prefetchBytes ?? undefined;
    if (this.#open !== o || t === null || bound === 0 || !o.store.time || t === o.store.time.index) return;
    const { stream } = o.session;
    const choice = { ...o.choice, time: t };
    this.#prefetch.start(o.source, {
      time: t,
      open: (metered) =>
        openZarrStore(metered, o.url, {
          rate: choice.storeRate,
          time: t,
          channel: choice.channel,
          ranges: o.ranges,
          decodeWorkers: true,
        }),
      wanted: (needsAt) => stream.wantedAhead(needsAt),
      learnt: (store) => learntOf(store, o.source),
      levels: o.store.levels.map((_, L) => L).filter((L) => L >= stream.finest),
      capacityBytes: bound,
    });
  }

  /** Whoever waits for the open store's refinements to end (whenIdle) hears it once none runs. */
  #settle(): void {
    const o = this.#open;
    if (o && o.running > 0) return;
    const waiting = this.#idle;
    this.#idle = [];
    for (const resolve of waiting) resolve();
  }

  #progress(o: OpenStore, p: StreamProgress): void {
    if (this.#open !== o) return;
    o.lastProgress = p;
    const where = o.guided ? ' where the rays hit' : '';
    if (p.phase === 'fetching')
      this.#line(`${o.url}: level ${p.level}${where}, ${p.chunksDone} / ${p.chunksNeeded} chunks, ${mib(o.session.metered.meter.bytes)}`);
    else if (p.phase === 'computing') this.#line(`${o.url}: level ${p.level}${where}, computing the surface…`);
    this.#publish(o);
  }

  /** The stream shows a step: the first with a surface becomes the volume on screen (level 0's frame), later ones update it. */
  #shown(o: OpenStore, s: ShownStep): void {
    if (this.#open !== o) return;
    // drawn only when whole: the steps before the plan's last wait (the time point before stays drawn)
    if (o.whole && !o.current && !s.final) return;
    const finest = s.levels[0]?.level ?? s.step;
    if (o.cut) {
      const levels = o.store.levels.map((_, L) => {
        const l = s.levels.find((x) => x.level === L);
        return { level: L, drawn: l ? l.drawn.length : 0, regions: s.leaves[L]?.length ?? 0, triangles: l?.stats.triangles ?? 0 };
      });
      o.state.cut = { tolerancePx: o.cut.tolerancePx, tint: o.cut.tint, levels, final: s.final };
    }
    if (o.state.reason && !o.state.reason.startsWith('the link')) o.state.reason = null;
    let installed = false;
    /** The slider's value asked while this store opened: refined once its state says what it shows. */
    let reask: number | undefined;
    if (o.current) {
      o.current.showAgain(s);
    } else if (s.levels.length > 0) {
      const { stream } = o.session;
      const iso = new StoreIsosurface(
        stream,
        s,
        o.valueRange,
        (value, others) => this.#refine(o, value, 'iso', others),
        (seen) => this.#refine(o, o.iso, { seen }),
        () => {
          // the page let the store go (another volume or store is on screen)
          if (this.#open === o) this.close();
          else this.#end(o);
        },
      );
      iso.tint = o.cut?.tint ?? false;
      // level 0's volume: the pieces of coarser levels are drawn at their own scale and place (store-isosurface.ts)
      const ranges = stream.chunkRanges(finest) ?? stream.chunkRanges(stream.coarsest) ?? o.coarse?.blockRanges ?? null;
      // the slider moved while this store opened: it opens there (the step drawn now is at the value it was opened at)
      const asked = this.#askedIso;
      this.#askedIso = undefined;
      const volume = storeVolume(o, iso, asked ?? s.iso, iso.stats, ranges);
      // another time point: the page keeps its camera, clip, voxel size and surfaces over a new volume's defaults
      const restore = o.keepPage ? this.d.keepPage?.(o.store.voxelSize) : undefined;
      this.d.install(volume);
      o.current = iso;
      o.installed = volume;
      if (restore) o.restoring = restore().catch((e: Error) => this.d.onError(`${o.url}: ${e.message}`));
      installed = true;
      if (asked !== undefined && asked !== s.iso) reask = asked;
      // the page's camera now (the link's, or Fit of the volume): plan the cut for it
      if (o.cut) this.#scheduleReplan(o);
    }
    // the link reopens the level on screen (level by level); the view decides in a cut
    this.d.setLevel(o.cut ? undefined : finest);
    if (o.state.shownLevels.at(-1) !== finest) o.state.shownLevels.push(finest);
    o.state.shownLevel = finest;
    o.state.parts = o.current?.placement ?? [];
    const sum = (f: (l: ShownStep['levels'][number]) => number) => s.levels.reduce((a, l) => a + f(l), 0);
    o.state.steps.push({ iso: s.iso, triangles: sum((l) => l.stats.triangles), vertices: sum((l) => l.stats.vertices) });
    if (o.state.steps.length > 64) o.state.steps.shift();
    o.state.stepsShown++;
    // the playback follows the store on screen once its state says what it shows
    if (installed) this.playback.storeShown();
    if (reask !== undefined) void this.#refine(o, reask);
    this.d.requestFrame();
    this.#widen(o);
    this.#publish(o);
    // the ranges of the bricks this step read are recorded once their readback arrives
    void o.session.stream.learnSettled().then(() => this.#widen(o));
  }

  /**
   * The slider's block profile from the finest level whose chunk ranges are
   * all known now (range arrays, or learnt as bricks arrived), in either
   * refinement; the value range stays.
   */
  #refreshProfile(o: OpenStore): void {
    const { stream } = o.session;
    const v = o.installed;
    if (this.#open !== o || !v) return;
    for (let L = stream.finest; L < o.store.levels.length; L++) {
      const ranges = stream.chunkRanges(L);
      if (!ranges) continue;
      if (ranges !== v.ranges) {
        v.ranges = ranges;
        this.d.widenValueRange(v, o.valueRange);
      }
      return;
    }
  }

  /**
   * A provisional value range (the coarsest level's, read at open) widened
   * by the brick ranges the stream has learnt since (as bricks arrive).
   * Final once every brick of level 0 is known.
   */
  #widen(o: OpenStore): void {
    this.#refreshProfile(o);
    const vr = o.state.valueRange;
    if (this.#open !== o || !vr?.provisional) return;
    const { learnt } = o.session.stream;
    const range = learnt.valueRange();
    const bricks = o.store.levels.reduce((a, _, L) => a + learnt.knownCount(L), 0);
    const complete = learnt.knownCount(0) === o.store.levels[0].chunkCount;
    if (!range) return;
    const lo = Math.min(vr.lo, range[0]);
    const hi = Math.max(vr.hi, range[1]);
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
    updatePageFigures(st, o.session);
    if (o.current) this.d.showGpuBytes(st.gpu.total);
    renderStorePanel(
      this.d.panel,
      o.store,
      st,
      o.session.fetcher.counters,
      (next) => {
        if (this.#open !== o) return;
        this.#keepIso = Number.isFinite(o.iso) ? o.iso : undefined;
        void this.openStore(o.source, o.url, { ...o.choice, ...next }, o.ranges);
      },
      (next) => this.#changeCut(o, next),
      this.playback.element,
    );
    this.d.publish({
      ...st,
      playback: this.playback.state,
      levels: st.levels.map((l) => ({ ...l })),
      shownLevels: [...st.shownLevels],
      gpu: { ...st.gpu },
      parts: st.parts.map((p) => ({ ...p })),
      steps: st.steps.map((p) => ({ ...p })),
    });
  }

  /** The camera moved: the cut is planned again at most every 150 ms (newest wins; the stream aborts what is no longer needed). */
  #scheduleReplan(o: OpenStore): void {
    if (o.replanTimer !== null || this.#open !== o || o.suspended || !o.cut) return;
    o.replanTimer = setTimeout(() => {
      o.replanTimer = null;
      if (this.#open !== o || !o.cut || !o.current) return;
      void this.#refine(o, o.iso, 'view');
    }, 150);
  }

  /** The line once a refinement ended: what is on screen, or why it stopped. */
  #endLine(o: OpenStore): void {
    const p = o.lastProgress;
    if (p?.phase === 'stopped' && p.reason)
      o.state.reason = p.retryInMs !== undefined ? `${p.reason} (trying again in ${Math.ceil(p.retryInMs / 1000)} s)` : p.reason;
    const fetched = mib(o.session.metered.meter.bytes);
    const why = o.state.reason ? `; ${o.state.reason}` : '';
    if (o.cut) {
      const on = o.state.cut?.levels.filter((l) => l.drawn > 0).map((l) => `level ${l.level}: ${l.drawn}`) ?? [];
      this.#line(`${o.url}: ${on.length > 0 ? `chunks on screen ${on.join(', ')}` : 'no surface in view'}, ${fetched} fetched${why}`);
      return;
    }
    const shown = o.state.shownLevel;
    if (shown === null) this.#line(`${o.url}: nothing shown${why}`);
    else if (shown === 0 && !o.state.reason) this.#line(`${o.url}: level 0 (full resolution), ${fetched} fetched`);
    else this.#line(`${o.url}: level ${shown} shown${why}`);
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
      if (o.current) o.current.tint = next.tint;
      this.d.requestFrame();
    }
    if (next.tolerancePx !== undefined && next.tolerancePx > 0) {
      o.cut.tolerancePx = next.tolerancePx;
      void this.#refine(o, o.iso, 'view');
    }
    this.d.setCut({ cut: true, tolerancePx: o.cut.tolerancePx, ...(o.cut.tint ? { tint: true } : {}) });
    if (o.state.cut) Object.assign(o.state.cut, { tolerancePx: o.cut.tolerancePx, tint: o.cut.tint });
    this.#publish(o);
  }

  #line(text: string): void {
    this.d.line.hidden = text === '';
    this.d.line.textContent = text;
  }
}

/** Two clips that cut the same (both absent, or the same box and plane). */
function sameClip(a: Clip | undefined, b: Clip | undefined): boolean {
  return JSON.stringify(a ?? null) === JSON.stringify(b ?? null);
}
