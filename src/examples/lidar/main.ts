// LIDAR page: drop a .las/.laz (decoded by LASzip in WebAssembly, streamed in
// chunks straight to the GPU) or generate a survey, and look at it as
// billboarded splats coloured by RGB, intensity, elevation or class.
import { setInfoList } from '../../app/info-list.ts';
import { LasError, LasReader, type LasHeader } from '../../loaders/las.ts';
import { BoxLayer } from '../../render/box-layer.ts';
import type { Bounds } from '../../render/camera.ts';
import {
  acceptFiles,
  byId,
  formatBytes,
  formatCount,
  formatLength,
  formatMs,
  nextFrame,
  Progress,
  publishState,
  runPage,
  startExampleViewer,
  type ExamplePageState,
} from '../common.ts';
import { generatePointCloud } from './generate.ts';
import { packAttributes, PointLayer, type ColorMode } from './point-layer.ts';

interface LidarState extends ExamplePageState {
  /** Points on the GPU. */
  pointCount: number;
  /** What is shown: a file name or "generated". */
  source?: string;
  /** Milliseconds from the start of the load to the last point on the GPU. */
  loadMs?: number;
  loading: boolean;
  colorMode: ColorMode;
}

declare global {
  interface Window {
    lidar?: LidarState;
  }
}

const CLASS_NAMES: Record<number, string> = {
  0: 'never classified',
  1: 'unclassified',
  2: 'ground',
  3: 'low vegetation',
  4: 'medium vegetation',
  5: 'high vegetation',
  6: 'building',
  7: 'low point (noise)',
  8: 'model key point',
  9: 'water',
  10: 'rail',
  11: 'road surface',
  12: 'overlap',
  13: 'wire guard',
  14: 'wire conductor',
  15: 'transmission tower',
  16: 'wire connector',
  17: 'bridge deck',
  18: 'high noise',
};
// Same palette as class_color() in shaders/points/splat.wgsl, for the legend.
const CLASS_COLORS: Record<number, [number, number, number]> = {
  0: [0.62, 0.62, 0.62],
  1: [0.62, 0.62, 0.62],
  2: [0.68, 0.52, 0.32],
  3: [0.55, 0.8, 0.35],
  4: [0.28, 0.68, 0.25],
  5: [0.1, 0.48, 0.16],
  6: [0.9, 0.3, 0.25],
  7: [1, 0.1, 0.8],
  8: [0.95, 0.85, 0.2],
  9: [0.2, 0.5, 0.95],
  10: [0.75, 0.45, 0.85],
  11: [0.45, 0.45, 0.5],
  12: [0.85, 0.85, 0.55],
  13: [0.95, 0.65, 0.2],
  14: [0.95, 0.65, 0.2],
  15: [0.9, 0.9, 0.9],
  16: [0.6, 0.9, 0.9],
  17: [0.55, 0.35, 0.25],
  18: [1, 0, 0],
};
function classColor(c: number): string {
  let rgb = CLASS_COLORS[c];
  if (!rgb) {
    const h = (c * 0.618034) % 1;
    rgb = [0, 2 / 3, 1 / 3].map((o) => 0.35 + 0.6 * Math.min(1, Math.max(0, Math.abs(((h + o) % 1) * 6 - 3) - 1))) as [
      number,
      number,
      number,
    ];
  }
  return `rgb(${rgb.map((v) => Math.round(v * 255)).join(',')})`;
}

/** Accumulates what the colour modes need while chunks stream in. */
class CloudStats {
  readonly intensityHistogram = new Uint32Array(65536);
  readonly classCounts = new Float64Array(256);
  readonly min: [number, number, number] = [Infinity, Infinity, Infinity];
  readonly max: [number, number, number] = [-Infinity, -Infinity, -Infinity];
  count = 0;

  add(n: number, positions: Float32Array, intensity?: Uint16Array, classification?: Uint8Array): void {
    for (let i = 0; i < n; i++) {
      for (let a = 0; a < 3; a++) {
        const v = positions[3 * i + a];
        if (v < this.min[a]) this.min[a] = v;
        if (v > this.max[a]) this.max[a] = v;
      }
      if (intensity) this.intensityHistogram[intensity[i]]++;
      if (classification) this.classCounts[classification[i]]++;
    }
    this.count += n;
  }

  /** Intensity window: 2nd to 98th percentile, so a few bright returns do not wash out the rest. */
  intensityRange(): [number, number] {
    if (this.count === 0) return [0, 65535];
    const lo = this.percentile(0.02);
    const hi = this.percentile(0.98);
    return hi > lo ? [lo, hi] : [lo, lo + 1];
  }

  private percentile(q: number): number {
    const target = q * this.count;
    let seen = 0;
    for (let v = 0; v < 65536; v++) {
      seen += this.intensityHistogram[v];
      if (seen >= target) return v;
    }
    return 65535;
  }
}

async function start(): Promise<void> {
  const state = publishState<LidarState>({ status: 'loading', framesDrawn: () => 0, pointCount: 0, loading: false, colorMode: 'rgb' });
  window.lidar = state;

  const started = await startExampleViewer(state, 'lidar.device', { r: 0.075, g: 0.082, b: 0.1, a: 1 });
  if (!started) return;
  const { stage, messages, gpu, viewer, cameraUrl } = started;
  const points = await PointLayer.create(viewer);
  const box = await BoxLayer.create(viewer);
  viewer.addLayer(points);
  viewer.addLayer(box);

  const progress = new Progress();
  const hud = byId('view-badge');
  const emptyHint = byId('empty-hint');
  const colorSelect = byId<HTMLSelectElement>('color-mode');
  const sizeInput = byId<HTMLInputElement>('point-size');
  const sizeValue = byId<HTMLOutputElement>('point-size-value');
  const legend = byId('legend');
  let stats = new CloudStats();
  let hasRGB = true;
  let loadToken = 0;
  let zUnit = 'm';

  let framesAtLastHud = 0;
  const updateHud = () => {
    if (state.pointCount === 0) {
      hud.hidden = true;
      return;
    }
    hud.hidden = false;
    // Frames are drawn on demand: a rate only means something while they flow.
    const drawing = viewer.framesDrawn !== framesAtLastHud;
    framesAtLastHud = viewer.framesDrawn;
    const fps = drawing && viewer.fps > 0 ? `${viewer.fps.toFixed(0)} fps` : 'idle';
    hud.textContent = `${formatCount(state.pointCount)} points · ${fps}${state.loadMs !== undefined ? ` · loaded in ${formatMs(state.loadMs)}` : ''}`;
  };
  setInterval(updateHud, 500);

  const renderLegend = () => {
    legend.replaceChildren();
    const mode = points.style.colorMode;
    if (state.pointCount === 0) return;
    if (mode === 'classification') {
      const list = document.createElement('div');
      list.className = 'legend';
      for (let c = 0; c < 256; c++) {
        const n = stats.classCounts[c];
        if (n === 0) continue;
        const hidden = c < 32 && (points.style.hiddenClasses >>> c) & 1;
        const sw = document.createElement('span');
        sw.className = `swatch${hidden ? ' off' : ''}`;
        sw.style.background = classColor(c);
        const label = document.createElement('label');
        label.className = hidden ? 'off' : '';
        label.textContent = `${c} ${CLASS_NAMES[c] ?? 'user defined'}`;
        label.title = c < 32 ? 'Click to show or hide this class' : '';
        const count = document.createElement('span');
        count.className = 'count';
        count.textContent = formatCount(n);
        if (c < 32) {
          label.addEventListener('click', () => {
            points.setStyle({ hiddenClasses: points.style.hiddenClasses ^ (1 << c) });
            renderLegend();
          });
        }
        list.append(sw, label, count);
      }
      legend.append(list);
    } else if (mode === 'elevation' || mode === 'intensity') {
      const ramp = document.createElement('div');
      ramp.className = 'ramp';
      ramp.style.background =
        mode === 'elevation'
          ? 'linear-gradient(90deg, rgb(41,89,158), rgb(77,158,92) 25%, rgb(219,204,115) 50%, rgb(148,97,61) 75%, rgb(247,247,247))'
          : 'linear-gradient(90deg, #000, #fff)';
      const labels = document.createElement('div');
      labels.className = 'ramp-labels';
      const [lo, hi] = mode === 'elevation' ? points.style.zRange.map((z) => z + centreZ) : points.style.intensityRange;
      const fmt = (v: number) => (mode === 'elevation' ? formatLength(v, zUnit) : formatCount(v));
      labels.innerHTML = `<span>${fmt(lo)}</span><span>${mode === 'elevation' ? 'elevation' : 'intensity (2–98 %)'}</span><span>${fmt(hi)}</span>`;
      legend.append(ramp, labels);
    }
  };
  let centreZ = 0;

  const setColorMode = (mode: ColorMode) => {
    if (mode === 'rgb' && !hasRGB) mode = 'elevation';
    colorSelect.value = mode;
    state.colorMode = mode;
    points.setStyle({ colorMode: mode });
    renderLegend();
  };

  const finishStyle = () => {
    points.setStyle({ intensityRange: stats.intensityRange(), zRange: [stats.min[2], stats.max[2]] });
    renderLegend();
  };

  /** Frames the cloud and outlines its bounds (positions are relative to the centre). */
  const frame = (bounds: Bounds, restoreCamera: boolean) => {
    box.setBounds(bounds, [0.42, 0.47, 0.55, 1]);
    viewer.camera.fit(bounds);
    if (restoreCamera) cameraUrl.restore();
    viewer.requestFrame();
  };

  const beginLoad = (total: number, source: string) => {
    const token = ++loadToken;
    stats = new CloudStats();
    points.reset(total);
    points.setStyle({ hiddenClasses: 0 });
    state.pointCount = 0;
    state.source = source;
    state.loadMs = undefined;
    state.loading = true;
    emptyHint.hidden = true;
    messages.clear();
    return token;
  };

  let firstLoad = true;
  // Progressive display while loading: a few frames a second at most, and
  // only once the GPU has finished the previous one (a slow GPU would
  // otherwise queue frame after frame of ever more points).
  let lastRedraw = 0;
  let gpuBusy = false;
  const redrawDue = () => {
    const now = performance.now();
    if (gpuBusy || now - lastRedraw < 250) return false;
    lastRedraw = now;
    gpuBusy = true;
    // The viewer's frame runs first in the next animation frame; wait for it on the GPU.
    requestAnimationFrame(() => void gpu.device.queue.onSubmittedWorkDone().then(() => (gpuBusy = false)));
    return true;
  };

  const loadFile = async (file: File) => {
    const t0 = performance.now();
    const token = beginLoad(0, file.name);
    progress.start(`Reading ${file.name}`);
    let reader: LasReader | undefined;
    try {
      // Streamed straight into the Wasm heap: the file's only copy.
      reader = await LasReader.open(file, file.name, (done, total) =>
        progress.set(done / total, `${formatBytes(done)} / ${formatBytes(total)}`),
      );
      if (token !== loadToken) return;
      progress.start(`Decoding ${file.name}`);
      const h = reader.header;
      points.reset(h.pointCount);
      hasRGB = h.hasRGB;
      colorSelect.querySelector<HTMLOptionElement>('option[value="rgb"]')!.disabled = !hasRGB;
      const local: Bounds = {
        min: [0, 1, 2].map((a) => h.bounds.min[a] - h.centre[a]) as [number, number, number],
        max: [0, 1, 2].map((a) => h.bounds.max[a] - h.centre[a]) as [number, number, number],
      };
      centreZ = h.centre[2];
      zUnit = 'm';
      frame(local, firstLoad);
      firstLoad = false;
      showInfo(h, file.size);
      if (!hasRGB && state.colorMode === 'rgb') setColorMode('elevation');
      // 16-bit RGB (the LAS convention) or 8-bit values (common practice): decide on the first chunk.
      let rgbShift = -1;
      const chunk = 1 << 18;
      let decodeMs = 0;
      for (;;) {
        const td = performance.now();
        const c = reader.read(chunk, { positions: true, rgb: hasRGB, intensity: true, classification: true });
        decodeMs += performance.now() - td;
        if (!c) break;
        if (rgbShift < 0) rgbShift = c.rgb?.some((v) => v > 255) ? 8 : 0;
        stats.add(c.count, c.positions!, c.intensity, c.classification);
        points.append(c.positions!, packAttributes(c.count, c.rgb, rgbShift, c.intensity, c.classification), c.count, redrawDue());
        state.pointCount = points.pointCount;
        progress.set(
          reader.pointsRead / Math.max(1, h.pointCount),
          `${formatCount(reader.pointsRead)} / ${formatCount(h.pointCount)} points`,
        );
        if (reader.pointsRead === c.count) finishStyle();
        await nextFrame();
        if (token !== loadToken) return;
      }
      finishStyle();
      // The file loaded, but something in it is wrong: say so instead of showing it as if it were fine.
      for (const w of reader.warnings) messages.show(`Warning: ${w}`, 'info');
      await gpu.device.queue.onSubmittedWorkDone();
      state.loadMs = performance.now() - t0;
      setInfoList(byId('cloud-info'), [
        ...infoRows,
        ['load time', `${formatMs(state.loadMs)} (decode ${formatMs(decodeMs)})`],
        ['decode rate', `${((h.pointCount / Math.max(decodeMs, 1e-3)) * 1e-3).toFixed(2)} M points/s`],
        ['GPU memory', formatBytes(points.gpuBytes)],
      ]);
      updateHud();
    } catch (e) {
      points.reset(0);
      state.pointCount = 0;
      emptyHint.hidden = false;
      const text = e instanceof LasError ? e.message : `${file.name}: ${(e as Error).message ?? String(e)}`;
      messages.show(`Could not load the point cloud. ${text}`);
    } finally {
      reader?.close();
      if (token === loadToken) {
        state.loading = false;
        progress.done();
      }
    }
  };

  let infoRows: [string, string][] = [];
  const showInfo = (h: LasHeader, fileBytes: number) => {
    const size = [0, 1, 2].map((a) => h.bounds.max[a] - h.bounds.min[a]);
    infoRows = [
      ['file', state.source ?? ''],
      ['points', formatCount(h.pointCount)],
      ['format', `LAS ${h.version}, point format ${h.pointFormat}${h.compressed ? ', LAZ' : ''}`],
      ['size', `${formatBytes(fileBytes)}${h.compressed ? ` (${(fileBytes / Math.max(1, h.pointCount)).toFixed(1)} B/point)` : ''}`],
      ['extent', size.map((s) => formatLength(s)).join(' × ')],
      ['centre', h.centre.map((c) => c.toFixed(2)).join(', ')],
    ];
    if (h.generatingSoftware) infoRows.push(['software', h.generatingSoftware]);
    setInfoList(byId('cloud-info'), infoRows);
  };

  const generate = async (count: number) => {
    const t0 = performance.now();
    const token = beginLoad(count, 'generated');
    hasRGB = true;
    colorSelect.querySelector<HTMLOptionElement>('option[value="rgb"]')!.disabled = false;
    progress.start(`Generating a ${formatCount(count)}-point survey`);
    const half = 1000;
    centreZ = 0;
    frame({ min: [-half, -half, -25], max: [half, half, 95] }, firstLoad);
    firstLoad = false;
    infoRows = [
      ['source', 'generated survey (terrain, lakes, roads, buildings, trees)'],
      ['points', formatCount(count)],
      ['extent', '2000 m × 2000 m'],
    ];
    setInfoList(byId('cloud-info'), infoRows);
    let styled = false;
    try {
      await generatePointCloud(count, {
        chunkSize: 1 << 18,
        yieldBetweenChunks: true,
        onChunk: (c) => {
          if (token !== loadToken) return;
          stats.add(c.count, c.positions!, c.intensity, c.classification);
          points.append(c.positions!, packAttributes(c.count, c.rgb, 0, c.intensity, c.classification), c.count, redrawDue());
          state.pointCount = points.pointCount;
          if (!styled) {
            finishStyle();
            styled = true;
          }
        },
        onProgress: (done, total) => progress.set(done / total, `${formatCount(done)} / ${formatCount(total)} points`),
        cancelled: () => token !== loadToken,
      });
      if (token !== loadToken) return;
      finishStyle();
      await gpu.device.queue.onSubmittedWorkDone();
      state.loadMs = performance.now() - t0;
      setInfoList(byId('cloud-info'), [
        ...infoRows,
        ['generated in', formatMs(state.loadMs)],
        ['GPU memory', formatBytes(points.gpuBytes)],
      ]);
      box.setBounds({ min: [...stats.min], max: [...stats.max] }, [0.42, 0.47, 0.55, 1]);
      updateHud();
    } finally {
      if (token === loadToken) {
        state.loading = false;
        progress.done();
      }
    }
  };

  acceptFiles(stage, byId('drop-overlay'), byId<HTMLInputElement>('file-input'), (files) => {
    const file = files.find((f) => /\.la[sz]$/i.test(f.name)) ?? files[0];
    if (files.length > 1) messages.show(`Showing ${file.name}; this page shows one point cloud at a time.`, 'info', 6000);
    void loadFile(file);
  });
  byId('generate').addEventListener('click', () => void generate(Number(byId<HTMLSelectElement>('generate-count').value)));
  colorSelect.addEventListener('change', () => setColorMode(colorSelect.value as ColorMode));
  const setSize = () => {
    const px = Number(sizeInput.value) * Math.min(2, devicePixelRatio);
    sizeValue.value = `${sizeInput.value} px`;
    points.setStyle({ sizePx: px });
  };
  sizeInput.addEventListener('input', setSize);
  setSize();
  for (const radio of document.querySelectorAll<HTMLInputElement>('input[name="shape"]')) {
    radio.addEventListener('change', () => points.setStyle({ shape: radio.value === 'square' ? 'square' : 'round' }));
  }

  state.status = 'ready';
  document.body.dataset.status = 'ready';
  viewer.requestFrame();

  const params = new URLSearchParams(location.search);
  const n = Number(params.get('generate'));
  if (params.has('generate') && Number.isInteger(n) && n > 0) {
    const select = byId<HTMLSelectElement>('generate-count');
    if (![...select.options].some((o) => o.value === String(n))) select.add(new Option(`${formatCount(n)} points`, String(n)));
    select.value = String(n);
    await generate(Math.min(n, 100_000_000));
  }
}

runPage(start);
