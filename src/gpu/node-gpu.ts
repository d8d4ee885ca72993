// WebGPU for Node (CLI, unit tests, benchmarks) through Dawn's `webgpu`
// package. On a machine without a GPU, Dawn is pointed at SwiftShader's Vulkan
// driver, which Debian's Chromium ships; with a GPU the GPU's driver is used.
import { existsSync, readdirSync } from 'node:fs';
import { requestGpu, WebGpuUnavailableError, type GpuContext, type RequestGpuOptions } from './device.ts';

export const SWIFTSHADER_ICD = '/usr/lib/chromium/vk_swiftshader_icd.json';

interface DawnModule {
  create(flags: string[]): GPU;
  globals: Record<string, unknown>;
}

let dawn: DawnModule | undefined;
/** One Dawn instance per process: several instances crash dawn.node. */
let instance: GPU | undefined;

async function loadDawn(): Promise<DawnModule> {
  if (!dawn) {
    try {
      dawn = (await import('webgpu')) as unknown as DawnModule;
    } catch (e) {
      throw new WebGpuUnavailableError(
        `Could not load Dawn (npm package "webgpu"): ${(e as Error).message}. ` +
          'Run "npm install"; on Debian also "apt-get install libvulkan1".',
      );
    }
    // GPUBufferUsage, GPUMapMode, ... as globals, like in a browser.
    for (const [k, v] of Object.entries(dawn.globals)) {
      if (!(k in globalThis)) (globalThis as Record<string, unknown>)[k] = v;
    }
  }
  return dawn;
}

function hasGpuDeviceNodes(): boolean {
  if (existsSync('/dev/nvidia0')) return true;
  try {
    return readdirSync('/dev/dri').some((n) => n.startsWith('renderD'));
  } catch {
    return false;
  }
}

export type NodeAdapterChoice = 'auto' | 'gpu' | 'swiftshader';

/** Which adapter to use: `ZFPISO_ADAPTER` = auto (default) | gpu | swiftshader. */
export function adapterChoiceFromEnv(): NodeAdapterChoice {
  const v = (process.env.ZFPISO_ADAPTER ?? 'auto').toLowerCase();
  if (v === 'gpu' || v === 'swiftshader' || v === 'auto') return v;
  throw new Error(`ZFPISO_ADAPTER must be auto, gpu or swiftshader (got "${v}")`);
}

function useSwiftShader(): void {
  if (!existsSync(SWIFTSHADER_ICD)) {
    throw new WebGpuUnavailableError(
      `No GPU adapter, and SwiftShader (${SWIFTSHADER_ICD}) is not installed. ` +
        'Install Debian\'s Chromium ("apt-get install chromium libvulkan1"), which ships it.',
    );
  }
  process.env.VK_ICD_FILENAMES = SWIFTSHADER_ICD;
  // Mesa's implicit device-select layer probes the display and only adds noise.
  process.env.VK_LOADER_LAYERS_DISABLE ??= '~implicit~';
}

/** Creates a device in Node: a real GPU when there is one, else SwiftShader. */
export async function requestNodeGpu(options: RequestGpuOptions = {}, choice = adapterChoiceFromEnv()): Promise<GpuContext> {
  const { create } = await loadDawn();
  const userSetIcd = process.env.VK_ICD_FILENAMES !== undefined;
  if (choice === 'swiftshader' || (choice === 'auto' && !userSetIcd && !hasGpuDeviceNodes())) {
    useSwiftShader();
  }
  try {
    instance ??= create([]);
    return await requestGpu(instance, options);
  } catch (e) {
    // No adapter from the system's drivers: fall back to SwiftShader, since the
    // Vulkan loader reads VK_ICD_FILENAMES again for each new instance.
    if (!(e instanceof WebGpuUnavailableError) || choice !== 'auto' || process.env.VK_ICD_FILENAMES === SWIFTSHADER_ICD) throw e;
    useSwiftShader();
    instance = create([]);
    return requestGpu(instance, options);
  }
}
