// The page's store view (`?store=URL`, a dropped or picked folder or .ozx):
// opens the store as a StoreSession (src/store/session.ts: level by level,
// or refined by the view when asked or when level 0 is large), installs
// each level or cut the stream shows as the volume on screen (store-surface.ts,
// store-cut.ts), so the slider, statistics and exports work as for any
// volume; a progress line and a panel (levels, network, memory). Errors name
// the store; the current surface stays. Its parts that are not behaviour: store-open.ts.
import type { AsyncReadable } from '@zarrita/storage';
import { storeRateChooser } from '../../store/rate.ts';
import { StoreSession } from '../../store/session.ts';
import type { StreamProgress } from '../../store/stream-port.ts';
import { StoreError } from '../../store/zarr/errors.ts';
import { HttpStore } from '../../store/zarr/http-store.ts';
import { type LevelValues, readLevelValues } from '../../store/level-values.ts';
import { DEFAULT_TOLERANCE_PX } from '../../store/stream/store-stream.ts';
import { type ShownCutOfPage, StoreCutIsosurface } from './store-cut.ts';
import { chooseIsovalue } from '../iso-choice.ts';
import { renderStorePanel, type StoreChoice, type StorePageState } from './store-panel.ts';
import { type ShownLevel, StoreLevelIsosurface } from './store-surface.ts';
import {
  initialPageState,
  updatePageFigures,
  storeChoiceOf,
  storeSourceOfUrl,
  learntOf,
  levelZeroIsLarge,
  pageViewSpec,
  mib,
  type OpenStore,
  type StoreViewDeps,
  storeVolume,
  WARNING_NOTE,
} from './store-open.ts';

export type { StoreViewDeps };

export type { StorePageState };

export type { StoreChoice };

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
    return this.openStore(storeSourceOfUrl(url), url, undefined, ranges);
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
          if (!(asked.cut ?? levelZeroIsLarge(store, this.d.budgetBytes()))) return null;
          cut = { tolerancePx: asked.tolerancePx ?? DEFAULT_TOLERANCE_PX, tint: asked.tint ?? false };
          return pageViewSpec(this.d.camera(), store, cut.tolerancePx, asked.camera);
        },
      });
    } catch (e) {
      // a failed open has let its store go (decode workers, requests)
      if (gen === this.#gen) this.#line('');
      this.d.onError(e instanceof StoreError ? e.message : `${url}: ${(e as Error).message}`);
      return;
    }
    const { store, metered, fetcher: f } = session;
    const controller = session.levels ?? session.stream;
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
    const state = initialPageState(url, store, controller, finest, cut, coarse);
    const shownChoice = storeChoiceOf(store);
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
    controller.onProgress((p) => this.#progress(o, p));
    // a chunk that failed is tried again by the stream once it has cooled down (the coarser surface stays meanwhile)
    if (session.levels) session.levels.onShown((s) => this.#shown(o, s));
    else session.stream.onShown((s) => this.#shownCut(o, s));
    controller.onError((e) => this.d.onError(e.message));
    this.#publish(o);

    // The isovalue: the link's (or the one kept over a reopen) as given, even outside a provisional range; else
    // Otsu over the finest known ranges (a store without any: its coarsest level shown first gives them).
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
        o.session.levels!,
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
      const k = o.store.levelScales[s.level];
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
    // the ranges of the bricks this level read are recorded once their readback arrives
    void o.session.stream.learnSettled().then(() => this.#widen(o));
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
    updatePageFigures(st, o.session);
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
    const { stream } = o.session;
    o.running++;
    o.state.done = false;
    this.#publish(o);
    try {
      await stream.setView(pageViewSpec(this.d.camera(), o.store, o.cut!.tolerancePx, undefined, true));
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
      const { stream } = o.session;
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
        [1, 1, 1],
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
    void o.session.stream.learnSettled().then(() => this.#widen(o));
  }

  #line(text: string): void {
    this.d.line.hidden = text === '';
    this.d.line.textContent = text;
  }
}
