// Pieces shared by the example pages (LIDAR, neuron): WebGPU start-up with
// errors shown to the user, file drops, the load progress bar and the view
// state in the URL hash (the same #cam=... as the main page). The element
// lookup, the number formats and the device start-up are the main page's
// (src/app/dom.ts, format.ts, start-gpu.ts), re-exported here.
import { byId } from '../app/dom.ts';
import { formatBytes } from '../app/format.ts';
import { setInfoList } from '../app/info-list.ts';
import { Messages, showFatal } from '../app/messages.ts';
import { startGpu as startPageGpu } from '../app/start-gpu.ts';
import { decodeViewState, encodeViewState } from '../app/url-state.ts';
import { describeAdapter, type GpuContext } from '../gpu/device.ts';
import { Viewer } from '../render/viewer.ts';

export { byId };
export { formatBytes, formatCount, formatMs } from '../app/format.ts';

/** State the page tests read (and the shape the shared test helpers expect). */
export interface ExamplePageState {
  status: 'loading' | 'ready' | 'error';
  adapter?: GpuContext['adapter'];
  framesDrawn: () => number;
}

export function publishState<T extends ExamplePageState>(state: T): T {
  // tests/e2e/page.ts waits on window.zfpiso, like on the main page.
  (window as unknown as { zfpiso: ExamplePageState }).zfpiso = state;
  return state;
}

/** Requests the device (app/start-gpu.ts) and lists the adapter; on failure the page says why and this returns undefined. */
export async function startGpu(stage: HTMLElement, messages: Messages, label: string): Promise<GpuContext | undefined> {
  const gpu = await startPageGpu(stage, messages, label, () => {
    document.body.dataset.status = 'error';
  });
  if (gpu) {
    setInfoList(byId('gpu-info'), [
      ['adapter', describeAdapter(gpu.adapter)],
      ['max buffer', formatBytes(gpu.limits.maxBufferSize)],
    ]);
  }
  return gpu;
}

/** Files dropped on `target` (or chosen with `input`) go to `onFiles`. */
export function acceptFiles(target: HTMLElement, overlay: HTMLElement, input: HTMLInputElement, onFiles: (files: File[]) => void): void {
  let depth = 0;
  const hasFiles = (e: DragEvent) => [...(e.dataTransfer?.types ?? [])].includes('Files');
  target.addEventListener('dragenter', (e) => {
    if (!hasFiles(e)) return;
    e.preventDefault();
    depth++;
    overlay.hidden = false;
  });
  target.addEventListener('dragover', (e) => {
    if (hasFiles(e)) e.preventDefault();
  });
  target.addEventListener('dragleave', () => {
    depth = Math.max(0, depth - 1);
    if (depth === 0) overlay.hidden = true;
  });
  target.addEventListener('drop', (e) => {
    e.preventDefault();
    depth = 0;
    overlay.hidden = true;
    const files = [...(e.dataTransfer?.files ?? [])];
    if (files.length > 0) onFiles(files);
  });
  input.addEventListener('change', () => {
    const files = [...(input.files ?? [])];
    input.value = '';
    if (files.length > 0) onFiles(files);
  });
}

/** The progress box over the view. */
export class Progress {
  private readonly box = byId('load-progress');
  private readonly what = byId('load-progress-what');
  private readonly text = byId('load-progress-text');
  private readonly bar = byId('load-progress-bar');

  start(what: string): void {
    this.what.textContent = what;
    this.set(0, '');
    this.box.hidden = false;
  }

  set(fraction: number, text: string): void {
    const pct = Math.max(0, Math.min(1, fraction)) * 100;
    this.bar.style.width = `${pct.toFixed(1)}%`;
    this.box.setAttribute('aria-valuenow', pct.toFixed(0));
    this.text.textContent = text;
  }

  done(): void {
    this.box.hidden = true;
  }
}

/** Keeps the camera in the URL hash (#cam=...) and restores it on load. */
export function syncCameraWithUrl(viewer: Viewer): { restore(): boolean; write(): void } {
  let timer: ReturnType<typeof setTimeout> | undefined;
  return {
    restore() {
      const s = decodeViewState(location.hash);
      if (!s.camera) return false;
      viewer.camera.setState(s.camera);
      viewer.requestFrame();
      return true;
    },
    write() {
      clearTimeout(timer);
      timer = setTimeout(() => {
        const params = new URLSearchParams(location.hash.replace(/^#/, ''));
        const cam = new URLSearchParams(encodeViewState({ camera: viewer.camera.getState() })).get('cam');
        if (cam) params.set('cam', cam);
        history.replaceState(null, '', `${location.pathname}${location.search}#${params.toString().replace(/%2C/g, ',')}`);
      }, 250);
    },
  };
}

export function formatLength(x: number, unit = 'm'): string {
  const a = Math.abs(x);
  const digits = a >= 100 ? 0 : a >= 10 ? 1 : 2;
  return `${x.toFixed(digits)} ${unit}`;
}

/** Lets the browser paint (progress bars) between chunks of synchronous work. */
export function nextFrame(): Promise<void> {
  return new Promise((r) => setTimeout(r, 0));
}

export interface ExampleViewer {
  stage: HTMLElement;
  messages: Messages;
  gpu: GpuContext;
  viewer: Viewer;
  /** The camera in the URL hash: restore() after the first fit, write() happens on every change. */
  cameraUrl: { restore(): boolean; write(): void };
}

/**
 * Start-up of the viewer pages (LIDAR, neuron): the device (failures shown
 * over the view), a Viewer whose camera is kept in the URL hash, and the test
 * state wired to it. Undefined when WebGPU is unavailable (the page says why).
 */
export async function startExampleViewer(
  state: ExamplePageState,
  deviceLabel: string,
  clearColor: GPUColor,
): Promise<ExampleViewer | undefined> {
  const stage = byId('stage');
  const messages = new Messages(byId('messages'));
  const gpu = await startGpu(stage, messages, deviceLabel);
  if (!gpu) {
    state.status = 'error';
    return undefined;
  }
  state.adapter = gpu.adapter;
  let cameraUrl: ReturnType<typeof syncCameraWithUrl> | undefined;
  const viewer = new Viewer(gpu.device, byId<HTMLCanvasElement>('view'), { clearColor, onCameraChange: () => cameraUrl?.write() });
  cameraUrl = syncCameraWithUrl(viewer);
  state.framesDrawn = () => viewer.framesDrawn;
  return { stage, messages, gpu, viewer, cameraUrl };
}

/** Runs a page's start-up; if it throws, its message replaces the view. */
export function runPage(start: () => Promise<void>): void {
  start().catch((e: unknown) => {
    showFatal(document.getElementById('stage') ?? document.body, `The page failed to start: ${(e as Error).message ?? String(e)}`);
  });
}
