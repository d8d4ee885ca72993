// Neuron page: a TIFF stack (libtiff in WebAssembly; one multi-page file or
// many single-page files ordered by name) ray-marched on the GPU through a
// transfer function, with SWC reconstructions as tubes or lines in the same
// space, so traces can be checked against the image.
//
// The stack is also compressed on the GPU and fed to the main page's
// isosurface pipeline (isosurface.ts), drawn in the same space.
//
// Opaque layers (the traces, the isosurface) draw into a depth pre-pass that
// the ray marcher reads, so rays stop at them: adding a layer means
// implementing DepthDrawer and RenderLayer and registering it like the
// SwcLayer below.
import { setInfoList } from '../../app/info-list.ts';
import { parseSwc, SwcError } from '../../loaders/swc.ts';
import { loadTiffStack, TiffError, type TiffVolume } from '../../loaders/tiff.ts';
import { BoxLayer } from '../../render/box-layer.ts';
import type { Bounds } from '../../render/camera.ts';
import { tiffVolumeFacts } from '../../volume/open-volume.ts';
import {
  acceptFiles,
  byId,
  formatBytes,
  formatCount,
  formatMs,
  nextFrame,
  Progress,
  publishState,
  runPage,
  startExampleViewer,
  type ExamplePageState,
} from '../common.ts';
import { makeDemoNeuron } from './demo.ts';
import { DepthPrepass } from './depth-prepass.ts';
import { NeuronIsosurface, type SurfaceState } from './isosurface.ts';
import { FILE_COLORS, SwcLayer, type Trace, type TraceColoring, type TraceStyle } from './swc-layer.ts';
import { COLORMAP_NAMES, drawTransferFunction, type ColormapName, type TransferFunction } from './transfer-function.ts';
import { renderTraceLegend, renderTraceList } from './trace-panel.ts';
import { VolumeLayer, type RenderMode, type VolumeSummary } from './volume-layer.ts';

type Vec3 = [number, number, number];

interface NeuronState extends ExamplePageState {
  loading: boolean;
  /** The volume on the GPU. */
  volume?: { name: string; dims: Vec3; dtype: string; spacing: Vec3; files: number; loadMs: number };
  traces: { name: string; samples: number; visible: boolean }[];
  demo: boolean;
  /** The isosurface of the stack on screen. */
  surface?: SurfaceState;
}

declare global {
  interface Window {
    neuron?: NeuronState;
  }
}

interface LoadedTrace extends Trace {
  name: string;
  demo: boolean;
}

async function start(): Promise<void> {
  const state = publishState<NeuronState>({ status: 'loading', framesDrawn: () => 0, loading: false, traces: [], demo: false });
  window.neuron = state;

  const started = await startExampleViewer(state, 'neuron.device', { r: 0.035, g: 0.04, b: 0.05, a: 1 });
  if (!started) return;
  const { stage, messages, gpu, viewer, cameraUrl } = started;

  const prepass = new DepthPrepass(viewer);
  const traces = await SwcLayer.create(viewer);
  prepass.add(traces);
  const progress = new Progress();
  const surface = await NeuronIsosurface.create(gpu, viewer, prepass, messages, progress, () => updateHud());
  state.surface = surface.state;
  const volume = await VolumeLayer.create(viewer, prepass);
  const box = await BoxLayer.create(viewer);
  // Opaque first, then the volume composited over them.
  viewer.addLayer(box);
  viewer.addLayer(traces);
  viewer.addLayer(surface.layer);
  viewer.addLayer(volume);

  const hud = byId('view-badge');
  const emptyHint = byId('empty-hint');
  const tfCanvas = byId<HTMLCanvasElement>('tf-canvas');
  const colormapSelect = byId<HTMLSelectElement>('colormap');
  const lo = byId<HTMLInputElement>('window-lo');
  const hi = byId<HTMLInputElement>('window-hi');
  const opacity = byId<HTMLInputElement>('opacity');
  const gamma = byId<HTMLInputElement>('gamma');
  const quality = byId<HTMLInputElement>('quality');
  const units = byId<HTMLSelectElement>('trace-units');

  const tf: TransferFunction = { colormap: 'fluorescence', gamma: 1.6 };
  let summary: VolumeSummary | undefined;
  let loaded: LoadedTrace[] = [];
  let spacing: Vec3 = [1, 1, 1];
  let unit = 'µm';
  let loadToken = 0;

  for (const name of COLORMAP_NAMES) colormapSelect.add(new Option(name[0].toUpperCase() + name.slice(1), name));
  colormapSelect.value = tf.colormap;

  // ------------------------------------------------------------ display state

  const dataValue = (s: number) => {
    if (!summary) return s.toFixed(2);
    const v = summary.range[0] + s * (summary.range[1] - summary.range[0]);
    return Math.abs(v) >= 100 || Number.isInteger(v) ? v.toFixed(0) : v.toPrecision(3);
  };
  const applyVolumeStyle = () => {
    let l = Number(lo.value);
    let h = Number(hi.value);
    if (h <= l) h = Math.min(1, l + 0.002);
    if (l >= h) l = Math.max(0, h - 0.002);
    volume.window = [l, h];
    volume.opacity = Number(opacity.value);
    volume.quality = Number(quality.value);
    tf.gamma = Number(gamma.value);
    tf.colormap = colormapSelect.value as ColormapName;
    volume.setTransferFunction(tf);
    byId<HTMLOutputElement>('window-lo-value').value = dataValue(l);
    byId<HTMLOutputElement>('window-hi-value').value = dataValue(h);
    byId<HTMLOutputElement>('opacity-value').value = opacity.value;
    byId<HTMLOutputElement>('gamma-value').value = gamma.value;
    byId<HTMLOutputElement>('quality-value').value = quality.value;
    drawTransferFunction(tfCanvas, tf, l, h, summary?.histogram);
    viewer.requestFrame();
  };
  for (const input of [lo, hi, opacity, gamma, quality]) input.addEventListener('input', applyVolumeStyle);
  colormapSelect.addEventListener('change', applyVolumeStyle);
  for (const radio of document.querySelectorAll<HTMLInputElement>('input[name="mode"]')) {
    radio.addEventListener('change', () => {
      volume.mode = radio.value as RenderMode;
      viewer.requestFrame();
    });
  }
  byId<HTMLInputElement>('show-volume').addEventListener('change', (e) => {
    volume.visible = (e.target as HTMLInputElement).checked;
    viewer.requestFrame();
  });
  new ResizeObserver(() => drawTransferFunction(tfCanvas, tf, volume.window[0], volume.window[1], summary?.histogram)).observe(tfCanvas);

  // ------------------------------------------------------------ traces

  const renderTraces = () => {
    traces.coordinateScale = units.value === 'voxel' ? spacing : [1, 1, 1];
    traces.setTraces(loaded);
    state.traces = loaded.map((t) => ({ name: t.name, samples: t.tree.count, visible: t.visible }));
    renderTraceList(byId('trace-list'), loaded, renderTraces);
    renderTraceLegend(byId('trace-legend'), loaded, traces.coloring === 'type');
    updateHud();
  };

  for (const radio of document.querySelectorAll<HTMLInputElement>('input[name="trace-style"]')) {
    radio.addEventListener('change', () => {
      traces.style = radio.value as TraceStyle;
      viewer.requestFrame();
    });
  }
  byId<HTMLSelectElement>('trace-color').addEventListener('change', (e) => {
    traces.coloring = (e.target as HTMLSelectElement).value as TraceColoring;
    renderTraces();
  });
  units.addEventListener('change', () => {
    renderTraces();
    fit(false);
  });

  // ------------------------------------------------------------ scene

  const sceneBounds = (): Bounds | undefined => {
    const boxes = [volume.hasVolume ? volume.bounds : undefined, traces.bounds].filter((b): b is Bounds => b !== undefined);
    if (boxes.length === 0) return undefined;
    return {
      min: [0, 1, 2].map((a) => Math.min(...boxes.map((b) => b.min[a]))) as Vec3,
      max: [0, 1, 2].map((a) => Math.max(...boxes.map((b) => b.max[a]))) as Vec3,
    };
  };
  let firstFit = true;
  const fit = (restore: boolean) => {
    const b = sceneBounds();
    emptyHint.hidden = b !== undefined;
    if (!b) return;
    viewer.camera.fit(b);
    if (restore && firstFit) cameraUrl.restore();
    firstFit = false;
    viewer.requestFrame();
  };

  let framesAtLastHud = 0;
  function updateHud(): void {
    const parts: string[] = [];
    if (state.volume) parts.push(`volume ${state.volume.dims.join('×')}`);
    const samples = loaded.filter((t) => t.visible).reduce((s, t) => s + t.tree.count, 0);
    if (samples > 0) parts.push(`${formatCount(samples)} trace samples`);
    const iso = surface.state;
    if (iso.computing) parts.push('isosurface…');
    else if (iso.visible && iso.triangles !== undefined) parts.push(`${formatCount(iso.triangles)} triangles`);
    if (parts.length === 0) {
      hud.hidden = true;
      return;
    }
    const drawing = viewer.framesDrawn !== framesAtLastHud;
    framesAtLastHud = viewer.framesDrawn;
    parts.push(drawing && viewer.fps > 0 ? `${viewer.fps.toFixed(0)} fps` : 'idle');
    hud.hidden = false;
    hud.textContent = parts.join(' · ');
  }
  setInterval(updateHud, 500);

  const showVolume = (
    name: string,
    v: {
      dims: Vec3;
      data: TiffVolume['data'];
      channels: number;
      spacing?: Vec3;
      unit?: string;
      dtype: string;
      files: number;
      decodeMs: number;
      loadMs: number;
      pages?: number;
    },
  ) => {
    spacing = v.spacing ?? [1, 1, 1];
    unit = v.unit ?? 'px (uncalibrated)';
    summary = volume.setVolume({ dims: v.dims, spacing, data: v.data, channels: v.channels });
    box.setBounds(volume.bounds, [0.33, 0.37, 0.44, 1]);
    [lo.value, hi.value] = summary.suggestedWindow.map(String);
    applyVolumeStyle();
    const reduced = summary.textureDims.some((d, a) => d !== v.dims[a]);
    state.volume = { name, dims: v.dims, dtype: v.dtype, spacing, files: v.files, loadMs: v.loadMs };
    setInfoList(byId('volume-info'), [
      ['stack', name],
      ['size', `${v.dims.join(' × ')} voxels${v.channels > 1 ? `, ${v.channels} channels (shown as their mean)` : ''}`],
      ['samples', `${v.dtype}, range ${dataValue(0)} – ${dataValue(1)}`],
      ['voxel', `${spacing.map((s) => Number(s.toPrecision(4))).join(' × ')} ${unit}`],
      ['load time', `${formatMs(v.loadMs)} (libtiff ${formatMs(v.decodeMs)})`],
      [
        'GPU texture',
        `${summary.textureDims.join(' × ')} ${summary.format}, ${formatBytes(summary.gpuBytes)}${reduced ? ' (reduced to fit the device)' : ''}`,
      ],
    ]);
  };

  // ------------------------------------------------------------ loading

  /**
   * Decodes and shows the stack, and starts its isosurface (at once, so the
   * surface on screen always belongs to the volume on screen); resolves with
   * the surface's computation, or undefined when a newer load replaced it.
   */
  const loadStack = async (files: File[], token: number): Promise<Promise<void> | undefined> => {
    const t0 = performance.now();
    const what = files.length === 1 ? files[0].name : `${files.length} TIFF files`;
    progress.start(`Decoding ${what}`);
    // Each File is streamed into the Wasm heap when its turn comes, and freed after.
    const v = await loadTiffStack(
      files.map((f) => ({ name: f.name, bytes: f })),
      {
        yieldBetweenPages: true,
        onProgress: (done, total) => progress.set(done / total, `${formatCount(done)} / ${formatCount(total)} pages`),
      },
    );
    if (token !== loadToken) return undefined;
    progress.start('Uploading to the GPU');
    await nextFrame();
    clearDemo();
    // The isosurface reads the same samples (multi-channel stacks: their mean, as the ray marcher shows them).
    const facts = tiffVolumeFacts(
      what,
      v,
      files.reduce((n, f) => n + f.size, 0),
      { channels: 'mean' },
    );
    showVolume(what, {
      dims: v.dims,
      data: v.data,
      channels: v.samplesPerPixel,
      spacing: v.spacing,
      unit: v.unit,
      dtype: v.dtype,
      files: v.files.length,
      decodeMs: v.decodeMs,
      loadMs: performance.now() - t0,
      pages: v.pages.length,
    });
    if (v.skippedPages > 0)
      messages.show(`${what}: ${v.skippedPages} page(s) of another size (thumbnails, previews) were left out.`, 'info', 8000);
    return surface.setStack({ name: what, facts, bytes: new Uint8Array(0), spacing });
  };

  const loadTraces = async (files: File[]) => {
    clearDemoTrace();
    for (const f of files) {
      try {
        const tree = parseSwc(await f.text(), f.name);
        // Not a sound tree: say what was found; only the valid links are drawn.
        if (tree.problems?.length) messages.show(`${f.name}: ${tree.problems.join('; ')}.`, 'info');
        loaded.push({ name: f.name, tree, visible: true, demo: false, color: FILE_COLORS[loaded.length % FILE_COLORS.length] });
      } catch (e) {
        messages.show(e instanceof SwcError ? `Could not read a trace. ${e.message}` : `${f.name}: ${(e as Error).message}`);
      }
    }
    renderTraces();
  };

  const clearDemoTrace = () => {
    if (!state.demo) return;
    loaded = loaded.filter((t) => !t.demo);
  };
  const clearDemo = () => {
    if (!state.demo) return;
    clearDemoTrace();
    state.demo = false;
    renderTraces();
  };

  const loadFiles = async (files: File[]) => {
    const token = ++loadToken;
    const tiffs = files.filter((f) => /\.tiff?$/i.test(f.name));
    const swcs = files.filter((f) => /\.swc$/i.test(f.name));
    const other = files.filter((f) => !tiffs.includes(f) && !swcs.includes(f));
    messages.clear();
    if (other.length > 0)
      messages.show(`Ignored ${other.map((f) => f.name).join(', ')}: this page reads .tif/.tiff stacks and .swc traces.`, 'info', 8000);
    state.loading = true;
    try {
      const surfaceDone = tiffs.length > 0 ? await loadStack(tiffs, token) : undefined;
      if (swcs.length > 0) await loadTraces(swcs);
      if (token === loadToken) fit(false);
      // The volume and traces are on screen; the isosurface follows (its errors are its own messages).
      await surfaceDone;
    } catch (e) {
      const text = e instanceof TiffError ? e.message : ((e as Error).message ?? String(e));
      messages.show(`Could not load the stack. ${text}`);
    } finally {
      if (token === loadToken) {
        state.loading = false;
        progress.done();
      }
    }
  };

  const showDemo = () => {
    ++loadToken;
    const t0 = performance.now();
    const demo = makeDemoNeuron();
    loaded = loaded.filter((t) => !t.demo);
    loaded.unshift({ name: demo.tree.fileName, tree: demo.tree, visible: true, demo: true, color: FILE_COLORS[0] });
    state.demo = true;
    units.value = 'physical';
    showVolume('demo cell (synthetic)', {
      dims: demo.dims,
      data: demo.volume,
      channels: 1,
      spacing: demo.spacing,
      unit: 'µm',
      dtype: 'uint8',
      files: 0,
      decodeMs: 0,
      loadMs: performance.now() - t0,
    });
    renderTraces();
    fit(true);
    void surface.setStack({
      name: 'the demo cell',
      facts: {
        fileName: 'demo cell (synthetic)',
        kind: 'raw',
        bytes: demo.volume.byteLength,
        dims: demo.dims,
        dtype: 'uint8',
        missing: [],
        compresses: true,
      },
      bytes: demo.volume,
      spacing: demo.spacing,
    });
  };

  acceptFiles(stage, byId('drop-overlay'), byId<HTMLInputElement>('file-input'), (files) => void loadFiles(files));
  byId('demo').addEventListener('click', showDemo);

  applyVolumeStyle();
  renderTraces();
  const params = new URLSearchParams(location.search);
  if (params.get('demo') !== '0') showDemo();
  else emptyHint.hidden = false;
  state.status = 'ready';
  document.body.dataset.status = 'ready';
  viewer.requestFrame();
}

runPage(start);
