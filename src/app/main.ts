// Page entry: the WebGPU device, the viewer and its layers, the panel, and
// the first volume (?url=… from this origin, else the built-in one). A lost
// device (a driver reset, or the tests' loseDevice hook) is not the end: a
// new device, the viewer and layers made again on it (same camera, style and
// panel), and what was on screen opened again (the file, URL, built-in
// volume or store) at the same isovalue and view, with a message.
import { GpuBudget } from '../gpu/budget.ts';
import { describeAdapter, type GpuContext } from '../gpu/device.ts';
import { ArcballCamera } from '../render/camera.ts';
import { BoxLayer } from '../render/box-layer.ts';
import { SurfaceLayer } from '../render/surface-layer.ts';
import { Viewer } from '../render/viewer.ts';
import { acceptDrops, hexToRgb, wireControls } from './controls.ts';
import { byId } from './dom.ts';
import { copyLink, measureShown, saveGlb, saveMeasures, savePly, savePng } from './exports.ts';
import { type MeasuredSurface, MeasurePanel } from './ui/measure-panel.ts';
import { SurfaceSet } from './surfaces/surface-set.ts';
import { ClipControl } from './ui/clip-control.ts';
import { clipProblems } from './url-state.ts';
import { ClipDrag } from './clip-drag.ts';
import { ClipHandleLayer } from '../render/clip-handles.ts';
import { CapLayer } from '../render/cap-layer.ts';
import { RayLayer } from '../render/ray-layer.ts';
import { PickPanel } from './ui/pick-panel.ts';
import { probeFor } from '../zfp/probe.ts';
import { ZfpGpuStream } from '../zfp/gpu-stream.ts';
import type { Clip } from '../core/clip.ts';
import { SurfacesPanel } from './ui/surfaces-panel.ts';
import { setInfoList } from './info-list.ts';
import { chooseIsovalue } from './iso-choice.ts';
import { VolumeLoader } from './loading/loader.ts';
import { keepPageView } from './store/keep-page.ts';
import { mountStoreView, prefetchParameter, rangesParameter, storeParameter } from './store/mount.ts';
import type { StoreView } from './store/store-view.ts';
import { Messages, showFatal } from './messages.ts';
import { type PageState, publishPageState } from './page-state.ts';
import { Session } from './session.ts';
import { startGpu } from './start-gpu.ts';
import { BenchPanel } from './ui/bench-panel.ts';
import type { SurfaceEngine } from '../bench/harness.ts';
import { BudgetControl, defaultBudgetBytes } from './ui/budget-control.ts';
import { Hud } from './ui/hud.ts';
import { IsoControl } from './ui/iso-control.ts';
import { ProgressView } from './ui/progress.ts';
import { SpacingControl } from './ui/spacing-control.ts';
import { StatsPanel } from './ui/stats-panel.ts';
import { VolumeForm } from './ui/volume-form.ts';
import { SeriesDialog } from './ui/series-dialog.ts';
import { FileSeriesOpener } from './loading/file-series.ts';
import { ViewLink } from './view-link.ts';

/** ?url= of this page, if any. */
function urlParameter(): string | undefined {
  return new URLSearchParams(location.search).get('url') ?? undefined;
}

/** Keeps ?url= only while the volume on screen came from it (so a copied link reopens that volume). */
function setUrlParameter(url: string | undefined): void {
  const params = new URLSearchParams(location.search);
  if (url) params.set('url', url);
  else params.delete('url');
  const search = params.toString();
  history.replaceState(null, '', `${location.pathname}${search ? `?${search}` : ''}${location.hash}`);
}

async function start(): Promise<void> {
  const stage = byId('stage');
  const state = publishPageState();
  const messages = new Messages(byId('messages'));
  const show = messages.show.bind(messages);
  messages.show = (text, kind, timeoutMs) => {
    state.messages.push(text);
    return show(text, kind, timeoutMs);
  };

  const fatal = () => {
    state.status = 'error';
  };
  // recoveries run one after the other (a new device may be lost while what was on screen reopens)
  let recovering = Promise.resolve();
  const lost = (m: string) => {
    recovering = recovering.then(() => recover(m));
  };
  const first = await startGpu(stage, messages, 'page.device', fatal, lost);
  if (!first) return;
  let gpu: GpuContext = first;
  const canvas = byId<HTMLCanvasElement>('view');
  const camera = new ArcballCamera();
  let link: ViewLink | undefined;
  let viewer!: Viewer;
  let surface!: SurfaceLayer;
  let box!: BoxLayer;
  /** The clip box's outline (shown while a clip box is on). */
  let clipBox!: BoxLayer;
  /** The clip's handles (an overlay, shown while a box or plane is on). */
  let clipHandles!: ClipHandleLayer;
  /** The caps where the clip cuts an in-core volume open (coloured by its values). */
  let caps!: CapLayer;
  /** The selected surface ray cast in the block cache (Draw: rays; volumes opened whole). */
  let rays!: RayLayer;
  /** Picking (made once the session exists; the viewer's clicks go to it). */
  let pickPanel: PickPanel | undefined;
  /** Drags on the clip's handles, Ctrl-drags on the box's faces (made with the clip control). */
  let clipDrag: ClipDrag | undefined;
  let boxVisible = true;
  /** Told after every camera change (the store view re-plans its cut). */
  const cameraListeners = new Set<() => void>();
  /** The viewer and its layers on `g` (again after a lost device: same camera, up axis, style, box). */
  const mountGraphics = async (g: GpuContext): Promise<void> => {
    const old = viewer ? { up: viewer.upAxis, style: surface.style, voxelSize: surface.voxelSize } : null;
    viewer?.destroy();
    viewer = new Viewer(g.device, canvas, {
      camera,
      onClick: (u, v) => void pickPanel?.click(u, v),
      grab: {
        grab: (u, v, modifier) => clipDrag?.grab(u, v, modifier) ?? false,
        grabMove: (u, v) => clipDrag?.move(u, v),
        grabEnd: () => clipDrag?.end(),
        hover: (u, v) => clipDrag?.hover(u, v),
      },
      onCameraChange: () => {
        link?.schedule();
        for (const l of cameraListeners) l();
      },
    });
    // Y up, as in ParaView and vtk.js (and CT scans like the bonsai); the Display section changes it.
    viewer.upAxis = old?.up ?? 'y';
    [box, surface, clipBox, caps, clipHandles, rays] = await Promise.all([
      BoxLayer.create(viewer),
      SurfaceLayer.create(viewer),
      BoxLayer.create(viewer),
      CapLayer.create(viewer),
      ClipHandleLayer.create(viewer),
      RayLayer.create(viewer),
    ]);
    if (old) {
      surface.style = old.style;
      surface.voxelSize = old.voxelSize;
    }
    viewer.addLayer(surface);
    viewer.addLayer(rays);
    viewer.addLayer(caps);
    if (boxVisible) viewer.addLayer(box);

    state.adapter = g.adapter;
    setInfoList(byId('gpu-info'), [
      ['adapter', describeAdapter(g.adapter)],
      ['max buffer', `${(g.limits.maxBufferSize / 2 ** 20).toFixed(0)} MiB`],
      ['max binding', `${(g.limits.maxStorageBufferBindingSize / 2 ** 20).toFixed(0)} MiB`],
      ['timing', g.features.timestampQuery ? 'GPU timestamps per stage' : 'queue wall time (no timestamp-query)'],
    ]);
  };
  await mountGraphics(gpu);
  link = new ViewLink(camera, () => ({ width: canvas.width, height: canvas.height }));
  state.framesDrawn = () => viewer.framesDrawn;
  state.camera = () => camera.getState();
  state.loseDevice = () => gpu.device.destroy();

  const initialView = ViewLink.initial();
  // Draw: the selected surface as triangles or ray cast in the block cache (the link's draw=rays)
  let drawMode: 'mesh' | 'rays' = initialView.draw ?? 'mesh';
  const drawSelect = byId<HTMLSelectElement>('draw-mode');
  // rays make no triangles: the panel says what still uses them
  const drawNote = byId<HTMLElement>('draw-note');
  drawSelect.value = drawMode;
  state.draw = drawMode;
  drawNote.hidden = drawMode !== 'rays';
  drawSelect.addEventListener('change', () => {
    drawMode = drawSelect.value === 'rays' ? 'rays' : 'mesh';
    state.draw = drawMode;
    drawNote.hidden = drawMode !== 'rays';
    link?.setDraw(drawMode === 'rays' ? 'rays' : undefined);
    viewer.requestFrame();
  });
  if (drawMode === 'rays') link.setDraw('rays');
  let pendingIso = initialView.iso;
  let storeView: StoreView | undefined;
  let volumeUrl: string | undefined;

  const isoControl = new IsoControl(
    {
      slider: byId('iso-slider'),
      number: byId('iso-value'),
      profile: byId('iso-profile'),
      readout: byId('profile-readout'),
      min: byId('iso-min'),
      max: byId('iso-max'),
    },
    (iso) => surfaces.setIsovalue(iso),
  );
  const spacing = new SpacingControl([byId('spacing-x'), byId('spacing-y'), byId('spacing-z')], byId('spacing-note'), (s) => {
    session.setSpacing(s);
    showClipBox();
  });
  // The page's one GPU memory budget: every store streams against it (a lower one frees at once, a store being
  // replaced holds only what it draws); an in-core volume's cache and vertices are capped by the same figure.
  const pageBudget = new GpuBudget(defaultBudgetBytes(gpu.limits));
  const budget = new BudgetControl(byId('budget-mb'), byId('budget-bar'), byId('budget-note'), pageBudget.bytes, (bytes) => {
    pageBudget.bytes = bytes;
    // an in-core volume: the copies of its other surfaces go if they no longer fit (the pipeline gets what
    // they leave), and the caps are made again within what is left
    const dropped = surfaces.fitBudget();
    if (dropped.length > 0)
      messages.show(
        `The surfaces at ${dropped.join(', ')} are no longer kept within ${(bytes / 2 ** 20).toFixed(0)} MiB: select one to draw it again.`,
        'info',
        8000,
      );
    if (clip) applyClip(clip);
  });
  const frames = {
    get fps() {
      return viewer.fps;
    },
    get framesDrawn() {
      return viewer.framesDrawn;
    },
  };
  const hud: Hud = new Hud(byId('hud'), frames, (text) => stats.setFps(text));
  const stats = new StatsPanel(byId('surface-stats'), byId('memory-stats'), byId('stage-times'), () => hud.fpsLabel);
  const bench: BenchPanel = new BenchPanel({
    context: () => {
      const v = session.current;
      if (!v) return undefined;
      // draw=rays: a frame per surface, timed (the rays read the cache the surface left; the page's canvas)
      const iso = v.iso;
      const engine: SurfaceEngine =
        drawMode === 'rays'
          ? {
              resetCache: () => iso.resetCache(),
              compute: (value) => iso.compute(value),
              draw: async () => (await viewer.timeNextFrame()).totalMs,
            }
          : iso;
      return {
        engine,
        draw: drawMode,
        baseName: (v.opened.kind === 'default' ? 'default' : v.opened.name).replace(/[^\w.-]+/g, '_'),
        valueRange: v.iso.info.valueRange,
        volume: {
          name: v.opened.name,
          kind: v.opened.kind,
          dims: v.iso.info.dims,
          rate: v.opened.rate,
          blocks: v.iso.info.blockCount,
          valueRange: v.iso.info.valueRange,
          compressedBytes: v.opened.compressedBytes,
        },
        adapter: { ...gpu.adapter },
      };
    },
    onRunning: (running) => {
      state.benchRunning = running;
      // the benchmark drives the pipeline: no surface is added, selected or removed meanwhile
      byId('surfaces-section').inert = running;
      isoControl.setEnabled(!running && session.current !== undefined);
      byId<HTMLInputElement>('budget-mb').disabled = running;
      if (!running && session.current) surfaces.setIsovalue(isoControl.value);
    },
    onSurface: () => viewer.requestFrame(),
    onDone: (result) => {
      state.bench = result;
    },
    onError: (m) => messages.show(m),
  });
  // Several surfaces of an in-core volume: the selected one live, the others drawn from their copies.
  const surfaces: SurfaceSet = new SurfaceSet({
    viewer: () => viewer,
    live: () => surface,
    makeLayer: () => SurfaceLayer.create(viewer),
    current: () => session.current,
    setLiveIsovalue: (iso) => session.setIsovalue(iso),
    showIso: (iso) => {
      isoControl.setValue(iso);
      state.iso = iso;
    },
    budgetBytes: () => budget.bytes,
    messages,
    onChange: () => {
      surfacesPanel.render();
      link?.setSurfaces(surfaces.specs(), surfaces.selected);
      viewer.requestFrame();
    },
  });
  Object.defineProperty(state, 'surfaces', {
    enumerable: true,
    get: () => ({
      entries: surfaces.entries.map((e) => {
        return {
          iso: e.iso,
          color: e.color,
          opacity: e.opacity,
          visible: e.visible,
          triangles: surfaces.trianglesOf(e) ?? (e === surfaces.selectedEntry ? state.stats?.triangles : undefined),
        };
      }),
      selected: surfaces.selected,
      copyBytes: surfaces.copyBytes,
    }),
  });
  const surfacesPanel = new SurfacesPanel(
    byId('surface-list'),
    byId<HTMLButtonElement>('add-surface'),
    byId('surfaces-note'),
    () => surfaces,
  );
  // The clip: every surface layer cuts its fragments, a store leaves out chunks it removes whole, exports cut the mesh.
  let clip: Clip | undefined;
  const showClipBox = () => {
    viewer.removeLayer(clipBox);
    viewer.removeOverlay(clipHandles);
    if (session.current && clipDrag?.refresh()) viewer.addOverlay(clipHandles);
    const v = session.current;
    if (!clip?.box || !v) return;
    const s = spacing.value;
    const o = v.opened.origin ?? [0, 0, 0];
    const b = clip.box;
    clipBox.setBounds(
      {
        min: [0, 1, 2].map((a) => (b[a] + o[a]) * s[a]) as [number, number, number],
        max: [0, 1, 2].map((a) => (b[a + 3] + o[a]) * s[a]) as [number, number, number],
      },
      [0.95, 0.68, 0.25, 1],
    );
    viewer.addLayer(clipBox);
  };
  // The caps within what the budget leaves: an in-core volume's from its stream; a store's from the pools of the
  // step on screen, a piece per level (made again as each step shows); why none, or null.
  // A store's caps are held against the page's budget (the stream plans within what they leave).
  let storeCapsHeld = 0;
  const holdStoreCaps = (bytes: number) => {
    if (storeCapsHeld > 0) pageBudget.meter.remove(storeCapsHeld);
    storeCapsHeld = bytes;
    if (bytes > 0) pageBudget.meter.add(bytes);
  };
  const makeCaps = (): string | null => {
    const v = session.current;
    const stream = v?.opened.stream;
    let noCaps: string | null;
    holdStoreCaps(0);
    if (v?.iso.capPieces) {
      noCaps = caps.setPieces(clip ? v.iso.capPieces(clip) : [], pageBudget.bytes - pageBudget.heldBytes);
      holdStoreCaps(caps.byteSize);
    } else {
      const left = budget.bytes - (v?.iso.budgetedBytes ?? 0) - surfaces.copyBytes;
      noCaps = caps.setClip(stream instanceof ZfpGpuStream ? stream : undefined, clip, left);
    }
    state.capBlocks = caps.blocks;
    return noCaps;
  };
  const applyClip = (c: Clip | undefined): void => {
    clip = c;
    surface.clip = c;
    const noCaps = makeCaps();
    if (noCaps) messages.show(`No caps: ${noCaps}.`, 'info', 6000);
    session.clip = c;
    storeView?.setClip(c);
    link?.setClip(c);
    state.clip = c;
    showClipBox();
    viewer.requestFrame();
  };
  const clipControl = new ClipControl(
    {
      boxOn: byId<HTMLInputElement>('clip-box-on'),
      box: ['x0', 'x1', 'y0', 'y1', 'z0', 'z1'].map((k) => byId<HTMLInputElement>(`clip-${k}`)),
      boxLabels: ['x', 'y', 'z'].map((k) => byId(`clip-${k}-label`)),
      planeOn: byId<HTMLInputElement>('clip-plane-on'),
      planeAxis: byId<HTMLSelectElement>('clip-plane-axis'),
      planeNormal: byId<HTMLInputElement>('clip-plane-normal'),
      planeOffset: byId<HTMLInputElement>('clip-plane-offset'),
      planeLabel: byId('clip-plane-label'),
      planeFlip: byId<HTMLButtonElement>('clip-plane-flip'),
    },
    applyClip,
    () => {
      // away from the eye, in voxel coordinates (a world direction times the voxel size)
      const c = camera.getState();
      const eye = camera.eyePosition();
      const s = spacing.value;
      return [0, 1, 2].map((a) => (c.target[a] - eye[a]) * s[a]) as [number, number, number];
    },
    messages,
  );
  pickPanel = new PickPanel(
    byId<HTMLInputElement>('pick-points'),
    byId('pick-info'),
    async (u, v) => {
      const hit = await viewer.pick(u, v);
      const vol = session.current;
      if (!hit || !vol) return null;
      const s = spacing.value;
      const o = vol.opened.origin ?? [0, 0, 0];
      const voxel = [0, 1, 2].map((a) => hit.world[a] / s[a] - o[a]) as [number, number, number];
      // in-core volumes: the value from the stream's decoded voxels; a store: from the finest level of the step on screen holding it
      const stream = vol.opened.stream;
      const probe = await probeFor(gpu.device);
      if (stream instanceof ZfpGpuStream) return { voxel, world: hit.world, value: await probe.sample(stream, voxel) };
      const read = (await vol.iso.valueAt?.(voxel, probe)) ?? null;
      return { voxel, world: hit.world, value: read?.value ?? null, ...(read ? { level: read.level } : {}) };
    },
    (points, distance) => {
      state.picks = { points, distance };
    },
  );
  byId('clip-caps').addEventListener('change', () => {
    // a store fetches the chunks the caps read only while they are drawn
    storeView?.setCaps(byId<HTMLInputElement>('clip-caps').checked);
    viewer.requestFrame();
  });
  clipDrag = new ClipDrag({
    camera,
    size: () => ({ width: canvas.width, height: canvas.height }),
    clip: () => clip,
    dims: () => clipControl.dims,
    placement: () => ({ voxelSize: spacing.value, origin: session.current?.opened.origin ?? [0, 0, 0] }),
    setFace: (axis, side, value) => clipControl.setBoxFace(axis, side, value),
    setPlane: (plane) => clipControl.setPlane(plane),
    layer: () => clipHandles,
    requestFrame: () => viewer.requestFrame(),
  });
  const measure = new MeasurePanel(
    {
      button: byId<HTMLButtonElement>('measure-surface'),
      list: byId('surface-measure'),
      json: byId<HTMLButtonElement>('measures-json'),
      csv: byId<HTMLButtonElement>('measures-csv'),
    },
    (): Promise<MeasuredSurface[] | null> => measureShown(session, surfaces, messages),
    (all) => {
      state.measures = all;
      state.measure = all.find((m) => m.selected) ?? all[0];
    },
    (format, all) => saveMeasures(session, format, all, { clip, picks: state.picks }),
  );
  const makeSession = () =>
    new Session({
      viewer,
      surface,
      box,
      isoControl,
      spacing,
      stats,
      budget,
      hud,
      bench,
      link: link!,
      messages,
      state,
      volumeInfo: byId('volume-info'),
      measure,
      surfaces,
      clip: clipControl,
      caps: () => caps,
      capsOn: () => byId<HTMLInputElement>('clip-caps').checked,
      rays: () => rays,
      drawMode: () => drawMode,
    });
  let session = makeSession();
  session.pendingClip = initialView.clip;
  for (const problem of clipProblems(location.hash)) messages.show(problem);
  surfacesPanel.render();
  session.pendingCamera = initialView.camera;
  session.pendingSpacing = initialView.spacing;

  let nextUrl: string | undefined;
  /** Opens what is on screen again (set whenever a volume or a store's first level is installed). */
  let reopen: (() => Promise<void>) | undefined;
  const volumeForm = new VolumeForm(byId<HTMLDialogElement>('volume-form'));
  const loader = new VolumeLoader({
    gpu: () => gpu,
    progress: new ProgressView(byId('progress')),
    form: volumeForm,
    memoryBudget: () => budget.bytes,
    chooseIso: (opened, iso, ranges) => {
      const [lo, hi] = iso.info.valueRange;
      const wanted = pendingIso;
      pendingIso = undefined;
      if (wanted !== undefined && wanted >= lo && wanted <= hi) return wanted;
      return opened.defaultIsovalue ?? chooseIsovalue(ranges, iso.info.valueRange);
    },
    onLoaded: (v) => {
      session.install(v);
      storeView?.close(); // a store still streaming stops (its level on screen, if any, was just let go)
      link?.setLevel(undefined); // a store's view sets it again after installing its level
      volumeUrl = nextUrl;
      setUrlParameter(volumeUrl);
      reopen = () => loader.reload();
    },
    onError: (m) => messages.show(m),
    onNotice: (m) => messages.show(m, 'info', 15000),
    onCancelled: (what) => messages.show(`Opening ${what} was cancelled; the current volume stays.`, 'info', 4000),
    onBusy: (busy) => {
      state.loading = busy;
      byId<HTMLButtonElement>('bench-run').disabled = busy || !session.current;
    },
  });

  /** Another volume, unless a benchmark is using the current one. */
  const open = (load: () => Promise<void>): void => {
    if (bench.isRunning) {
      messages.show('A benchmark is running: cancel it before opening another volume.', 'info', 4000);
      return;
    }
    nextUrl = undefined;
    void load();
  };
  const openFilesAsBefore = (files: File[]): void => {
    const stack = files.length > 1 && files.every((f) => /\.tiff?$/i.test(f.name));
    if (files.length > 1 && !stack)
      messages.show(`Opening ${files[0].name} (one volume at a time; ${files.length - 1} other file(s) ignored).`, 'info', 4000);
    open(() => loader.loadFiles(files));
  };
  // numbered volume files dropped together play as a time series, through the store path (loading/file-series.ts)
  const seriesDialog = new SeriesDialog();
  const series = new FileSeriesOpener({
    askShape: (facts) => volumeForm.ask(facts),
    askSeries: (n, first, last, why) => seriesDialog.ask(n, first, last, why),
    onError: (m) => messages.show(m),
    onNotice: (m) => messages.show(m, 'info', 4000),
    openStore: (store, name, rate) => storeView!.openStore(store, name, rate === undefined ? {} : { storeRate: rate }),
  });
  const openFiles = (files: File[]): void => {
    series.supersede();
    seriesDialog.cancel();
    if (files.length < 2 || bench.isRunning) {
      openFilesAsBefore(files);
      return;
    }
    void series.open(files).then(
      (r) => {
        if (r.kind === 'files') openFilesAsBefore(files);
        else if (r.kind === 'first') open(() => loader.loadFile(r.file));
      },
      (e: Error) => messages.show(e.message),
    );
  };
  acceptDrops(byId('drop-overlay'), openFiles);
  wireControls({
    openFiles,
    loadDefault: () => open(() => loader.loadDefault()),
    resetView: () => viewer.controls.reset(),
    fitView: () => {
      viewer.fitView();
      link?.schedule();
    },
    savePng: () => void savePng(viewer, session, messages),
    savePly: () => void savePly(session, messages),
    saveGlb: () => void saveGlb(session, surfaces, messages),
    copyLink: () => {
      if (session.current && session.current.opened.kind !== 'default' && !volumeUrl) {
        messages.show(
          'The link keeps the view and isovalue; the volume came from a local file, so open it again after following the link.',
          'info',
          6000,
        );
      }
      void copyLink(link!, messages);
    },
    stepIso: (steps) => isoControl.step(steps),
    stepClipPlane: (steps) => clipControl.stepPlane(steps),
    setBoxVisible: (on) => {
      boxVisible = on;
      if (on) viewer.addLayer(box);
      else viewer.removeLayer(box);
    },
    setSmooth: (on) => {
      surface.style.smooth = on;
      viewer.requestFrame();
    },
    cancelLoad: () => {
      if (loader.busy) loader.cancel();
    },
    setUpAxis: (up) => {
      viewer.setUpAxis(up);
      link?.schedule();
    },
    setColors: (front, back) => {
      surfaces.setStyle(surfaces.selected, { color: hexToRgb(front) });
      surface.style.back = hexToRgb(back);
      viewer.requestFrame();
    },
  });

  /**
   * The device was lost: a new one, the graphics made again on it, and what
   * was on screen opened again at the same isovalue and view. Losses in
   * quick succession (a device that keeps failing) end in the fatal message.
   */
  const losses: number[] = [];
  async function recover(reason: string): Promise<void> {
    const now = performance.now();
    losses.push(now);
    while (losses.length > 0 && now - losses[0] > 60_000) losses.shift();
    state.deviceLosses = (state.deviceLosses ?? 0) + 1;
    if (losses.length > 3) {
      fatal();
      showFatal(stage, `${reason} It was lost ${losses.length} times within a minute; reload the page to try again.`);
      return;
    }
    state.status = 'loading';
    document.body.dataset.status = 'recovering';
    messages.show(
      `${reason.replace(/ reload the page to continue\.?$/i, '')} A new GPU device is being started; what was on screen opens again.`,
      'info',
      15000,
    );
    // what to open again, taken before the old session lets it go
    const store = storeView?.reopener() ?? null;
    const again = store ? store.open : reopen;
    const iso = store ? store.iso : session.drawnIsovalue;
    const view = camera.getState();
    const userSpacing = session.current ? spacing.value : undefined;
    // the surfaces: the selected one reopens with the volume, the others are made again around it
    const shownSurfaces = surfaces.specs();
    const selectedSurface = surfaces.selected;
    loader.cancel();
    storeView?.close();
    session.destroy();
    const next = await startGpu(stage, messages, 'page.device', fatal, lost);
    if (!next) return;
    gpu = next;
    await mountGraphics(gpu);
    session = makeSession();
    session.pendingClip = clip;
    session.pendingCamera = view;
    session.pendingSpacing = userSpacing;
    pendingIso = iso;
    if (again) await again();
    if (!session.current) {
      nextUrl = undefined;
      await loader.loadDefault();
    } else if (shownSurfaces.length > 1) await surfaces.restore(shownSurfaces, selectedSurface);
    if ((state.status as PageState['status']) !== 'error') {
      state.status = 'ready';
      document.body.dataset.status = 'ready';
    }
  }

  // The first volume: ?store= or ?url= when given (falling back to the built-in one if it fails).
  const url = urlParameter();
  const storeUrl = storeParameter();
  storeView = mountStoreView({
    gpu: () => gpu,
    budget: pageBudget,
    prefetchBytes: prefetchParameter(),
    onError: (m) => messages.show(m),
    onNotice: (m) => messages.show(m, 'info', 8000),
    // a store's first step with a surface becomes the volume on screen (level 0's frame); its later steps update it
    install: (v) => {
      session.install(v);
      // each step of the store: its caps from its own pools (the step before's chunks may be gone)
      v.iso.onStats(() => {
        if (clip && session.current === v) makeCaps();
      });
      const view = storeView!;
      reopen = async () => {
        const again = view.reopener();
        if (again) await again.open();
      };
    },
    setLevel: (level) => link?.setLevel(level),
    showGpuBytes: (bytes) => budget.setUsed(bytes, 'held on the GPU by the streamed store'),
    // a store's range is often provisional (its coarsest level's): the link's isovalue is used as given
    linkIso: () => {
      const wanted = pendingIso;
      pendingIso = undefined;
      return wanted !== undefined && Number.isFinite(wanted) ? wanted : undefined;
    },
    widenValueRange: (v, range) => session.widenValueRange(v, range),
    linkLevel: () => initialView.level,
    camera: () => ({ state: camera.getState(), viewport: { width: canvas.width, height: canvas.height } }),
    onCameraChange: (l) => {
      cameraListeners.add(l);
      return () => cameraListeners.delete(l);
    },
    linkCut: () => ({ cut: initialView.cut, tolerancePx: initialView.tolerancePx, tint: initialView.tint, camera: initialView.camera }),
    setCut: (cut) => link?.setCut(cut),
    requestFrame: () => viewer.requestFrame(),
    linkStoreChoice: () => ({ storeRate: initialView.storeRate, time: initialView.time, channel: initialView.channel }),
    setStoreChoice: (choice) => link?.setStoreChoice(choice),
    keepPage: (vox) => keepPageView({ session, camera: camera.getState(), clip, spacing: spacing.value, surfaces }, vox),
  });
  storeView.setCaps(byId<HTMLInputElement>('clip-caps').checked);
  storeView.playback.setCapture({ canvas, draw: () => viewer.drawNow() }); // Record's movie frames (store/recorder.ts)
  if (storeUrl) {
    await storeView.open(storeUrl, rangesParameter());
  } else if (url) {
    nextUrl = url;
    await loader.loadUrl(url);
  }
  if (!session.current) {
    nextUrl = undefined;
    await loader.loadDefault();
  }
  // the link's other surfaces, around the one the volume opened with
  if (initialView.surfaces && initialView.surfaces.length > 1 && session.current) {
    await surfaces.restore(initialView.surfaces, initialView.selected ?? 0);
  }
  if (state.status !== 'error') {
    state.status = 'ready';
    document.body.dataset.status = 'ready';
  }
}

start().catch((e: unknown) => {
  const stage = document.getElementById('stage') ?? document.body;
  showFatal(stage, `The page failed to start: ${(e as Error).message ?? String(e)}`);
});
