// Page entry: the WebGPU device, the viewer and its layers, the panel, and
// the first volume (?url=… from this origin, else the built-in one).
import { describeAdapter } from '../gpu/device.ts';
import { BoxLayer } from '../render/box-layer.ts';
import { SurfaceLayer } from '../render/surface-layer.ts';
import { Viewer } from '../render/viewer.ts';
import { acceptDrops, hexToRgb, wireControls } from './controls.ts';
import { byId } from './dom.ts';
import { copyLink, savePly, savePng } from './exports.ts';
import { setInfoList } from './info-list.ts';
import { chooseIsovalue } from './iso-choice.ts';
import { VolumeLoader } from './loading/loader.ts';
import { mountStoreView, storeParameter } from './store/mount.ts';
import type { StoreView } from './store/store-view.ts';
import { Messages, showFatal } from './messages.ts';
import { publishPageState } from './page-state.ts';
import { Session } from './session.ts';
import { startGpu } from './start-gpu.ts';
import { BenchPanel } from './ui/bench-panel.ts';
import { BudgetControl, defaultBudgetBytes } from './ui/budget-control.ts';
import { Hud } from './ui/hud.ts';
import { IsoControl } from './ui/iso-control.ts';
import { ProgressView } from './ui/progress.ts';
import { SpacingControl } from './ui/spacing-control.ts';
import { StatsPanel } from './ui/stats-panel.ts';
import { VolumeForm } from './ui/volume-form.ts';
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

  const gpu = await startGpu(stage, messages, 'page.device', () => {
    state.status = 'error';
  });
  if (!gpu) return;
  state.adapter = gpu.adapter;
  setInfoList(byId('gpu-info'), [
    ['adapter', describeAdapter(gpu.adapter)],
    ['max buffer', `${(gpu.limits.maxBufferSize / 2 ** 20).toFixed(0)} MiB`],
    ['max binding', `${(gpu.limits.maxStorageBufferBindingSize / 2 ** 20).toFixed(0)} MiB`],
    ['timing', gpu.features.timestampQuery ? 'GPU timestamps per stage' : 'queue wall time (no timestamp-query)'],
  ]);

  let link: ViewLink | undefined;
  const viewer = new Viewer(gpu.device, byId<HTMLCanvasElement>('view'), { onCameraChange: () => link?.schedule() });
  // Y up, as in ParaView and vtk.js (and CT scans like the bonsai); the Display section changes it.
  viewer.upAxis = 'y';
  link = new ViewLink(viewer.camera);
  state.framesDrawn = () => viewer.framesDrawn;
  state.camera = () => viewer.camera.getState();
  const [box, surface] = await Promise.all([BoxLayer.create(viewer), SurfaceLayer.create(viewer)]);
  viewer.addLayer(surface);
  viewer.addLayer(box);

  const initialView = ViewLink.initial();
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
    (iso) => session.setIsovalue(iso),
  );
  const spacing = new SpacingControl([byId('spacing-x'), byId('spacing-y'), byId('spacing-z')], byId('spacing-note'), (s) =>
    session.setSpacing(s),
  );
  const budget = new BudgetControl(byId('budget-mb'), byId('budget-bar'), byId('budget-note'), defaultBudgetBytes(gpu.limits), (bytes) =>
    session.current?.iso.setMemoryBudget(bytes),
  );
  const hud: Hud = new Hud(byId('hud'), viewer, (text) => stats.setFps(text));
  const stats = new StatsPanel(byId('surface-stats'), byId('memory-stats'), byId('stage-times'), () => hud.fpsLabel);
  const bench: BenchPanel = new BenchPanel({
    context: () => {
      const v = session.current;
      if (!v) return undefined;
      return {
        engine: v.iso,
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
      isoControl.setEnabled(!running && session.current !== undefined);
      byId<HTMLInputElement>('budget-mb').disabled = running;
      if (!running && session.current) session.setIsovalue(isoControl.value);
    },
    onSurface: () => viewer.requestFrame(),
    onDone: (result) => {
      state.bench = result;
    },
    onError: (m) => messages.show(m),
  });
  const session = new Session({
    viewer,
    surface,
    box,
    isoControl,
    spacing,
    stats,
    budget,
    hud,
    bench,
    link,
    messages,
    state,
    volumeInfo: byId('volume-info'),
  });
  session.pendingCamera = initialView.camera;
  session.pendingSpacing = initialView.spacing;

  let nextUrl: string | undefined;
  const loader = new VolumeLoader({
    gpu,
    progress: new ProgressView(byId('progress')),
    form: new VolumeForm(byId<HTMLDialogElement>('volume-form')),
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
  const openFiles = (files: File[]): void => {
    const stack = files.length > 1 && files.every((f) => /\.tiff?$/i.test(f.name));
    if (files.length > 1 && !stack)
      messages.show(`Opening ${files[0].name} (one volume at a time; ${files.length - 1} other file(s) ignored).`, 'info', 4000);
    open(() => loader.loadFiles(files));
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
    setBoxVisible: (on) => {
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
      surface.style.front = hexToRgb(front);
      surface.style.back = hexToRgb(back);
      viewer.requestFrame();
    },
  });

  // The first volume: ?store= or ?url= when given (falling back to the built-in one if it fails).
  const url = urlParameter();
  const storeUrl = storeParameter();
  storeView = mountStoreView({
    gpu,
    budgetBytes: () => budget.bytes,
    onError: (m) => messages.show(m),
    onNotice: (m) => messages.show(m, 'info', 8000),
    // each level the store's controller shows becomes the volume on screen; a finer or coarser one keeps the camera
    install: (v, level, first) => {
      if (!first) session.pendingCamera = viewer.camera.getState();
      session.install(v);
      link?.setLevel(level);
    },
    linkIso: ([lo, hi]) => {
      const wanted = pendingIso;
      pendingIso = undefined;
      return wanted !== undefined && wanted >= lo && wanted <= hi ? wanted : undefined;
    },
    linkLevel: () => initialView.level,
  });
  if (storeUrl) {
    await storeView.open(storeUrl);
  } else if (url) {
    nextUrl = url;
    await loader.loadUrl(url);
  }
  if (!session.current) {
    nextUrl = undefined;
    await loader.loadDefault();
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
