// Page entry: WebGPU device, viewer, the built-in volume, and the panel.
import { BROWSER_HELP, describeAdapter, requestGpu, WebGpuUnavailableError, type GpuContext } from '../gpu/device.ts';
import { BoxLayer } from '../render/box-layer.ts';
import { Viewer } from '../render/viewer.ts';
import { generateDefaultVolume } from '../volume/procedural.ts';
import { setInfoList } from './info-list.ts';
import { Messages, showFatal } from './messages.ts';

function byId<T extends HTMLElement>(id: string): T {
  const el = document.getElementById(id);
  if (!el) throw new Error(`page is missing #${id}`);
  return el as T;
}

/** State the end-to-end tests read (also handy in the console). */
export interface PageState {
  status: 'loading' | 'ready' | 'error';
  adapter?: GpuContext['adapter'];
  framesDrawn: () => number;
}

declare global {
  interface Window {
    zfpiso?: PageState;
  }
}

async function start(): Promise<void> {
  const stage = byId('stage');
  const messages = new Messages(byId('messages'));
  const state: PageState = { status: 'loading', framesDrawn: () => 0 };
  window.zfpiso = state;

  let gpu: GpuContext;
  try {
    gpu = await requestGpu(navigator.gpu, {
      label: 'page.device',
      onFailure: (f) => {
        if (f.kind === 'device-lost') showFatal(stage, f.message);
        else messages.show(`WebGPU ${f.kind} error: ${f.message}`);
      },
    });
  } catch (e) {
    state.status = 'error';
    showFatal(stage, e instanceof WebGpuUnavailableError ? e.message : `Could not start WebGPU: ${(e as Error).message}. ${BROWSER_HELP}`);
    return;
  }
  state.adapter = gpu.adapter;
  setInfoList(byId('gpu-info'), [
    ['adapter', describeAdapter(gpu.adapter)],
    ['max binding', `${(gpu.limits.maxStorageBufferBindingSize / 2 ** 20).toFixed(0)} MiB`],
    ['timing', gpu.features.timestampQuery ? 'GPU timestamps' : 'queue wall time'],
  ]);

  const viewer = new Viewer(gpu.device, byId<HTMLCanvasElement>('view'));
  state.framesDrawn = () => viewer.framesDrawn;
  const box = await BoxLayer.create(viewer);
  viewer.addLayer(box);

  const volume = generateDefaultVolume();
  const bounds = { min: [0, 0, 0] as [number, number, number], max: volume.dims.map((d) => d - 1) as [number, number, number] };
  box.setBounds(bounds);
  viewer.fitTo(bounds);
  setInfoList(byId('volume-info'), [
    ['name', volume.name],
    ['dims', volume.dims.join(' × ')],
  ]);
  state.status = 'ready';
  document.body.dataset.status = 'ready';
}

start().catch((e: unknown) => {
  const stage = document.getElementById('stage') ?? document.body;
  showFatal(stage, `The page failed to start: ${(e as Error).message ?? String(e)}`);
});
