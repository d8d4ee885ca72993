// WebGPU for Node (CLI, unit tests, benchmarks) through Dawn's `webgpu`
// package. On a machine without a GPU, Dawn is pointed at SwiftShader's Vulkan
// driver, which Debian's Chromium ships; with a GPU the GPU's driver is used.
import { spawnSync } from 'node:child_process';
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

/**
 * Dawn's instance flags from `ZFPISO_DAWN_FLAGS` (space-separated, e.g.
 * `disable-dawn-features=timestamp_quantization`, which bench:gpu sets so
 * that GPU timestamps are not rounded to 65.5 microseconds); none by default.
 */
export function dawnFlagsFromEnv(): string[] {
  return (process.env.ZFPISO_DAWN_FLAGS ?? '').split(/\s+/).filter(Boolean);
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

function hasVulkanLoader(): boolean {
  const r = spawnSync('ldconfig', ['-p'], { encoding: 'utf8' });
  // The cache can list a library that was removed since: check the file.
  if (r.status === 0) return [...r.stdout.matchAll(/libvulkan\.so\.1 .*=> (\S+)/g)].some((m) => existsSync(m[1]));
  return ['/usr/lib/x86_64-linux-gnu/libvulkan.so.1', '/usr/lib/aarch64-linux-gnu/libvulkan.so.1', '/usr/lib64/libvulkan.so.1'].some((p) =>
    existsSync(p),
  );
}

/** Why Dawn found no adapter, and what to install: advice for a command line, not a browser. */
export function nodeGpuHelp(): string {
  const missing = [...(hasVulkanLoader() ? [] : ['libvulkan1']), ...(existsSync(SWIFTSHADER_ICD) ? [] : ['chromium'])];
  const icd = process.env.VK_ICD_FILENAMES;
  return (
    'Dawn (WebGPU in Node) found no Vulkan adapter. ' +
    (missing.length > 0
      ? `Missing: ${missing.includes('libvulkan1') ? 'the Vulkan loader libvulkan.so.1 (Debian package libvulkan1)' : ''}${missing.length === 2 ? ' and ' : ''}${missing.includes('chromium') ? `SwiftShader's Vulkan driver ${SWIFTSHADER_ICD} (Debian package chromium)` : ''}. ` +
        `Install: sudo apt-get install -y ${missing.join(' ')} (npm run cli and npm test do it themselves when run as root).`
      : `The Vulkan loader and SwiftShader are installed${icd ? `; VK_ICD_FILENAMES=${icd} is set: check that it names a working driver` : ''}. ` +
        'ZFPISO_ADAPTER=swiftshader forces SwiftShader; with a GPU, check its Vulkan driver (vulkaninfo).')
  );
}

/** Creates a device in Node: a real GPU when there is one, else SwiftShader. */
export async function requestNodeGpu(options: RequestGpuOptions = {}, choice = adapterChoiceFromEnv()): Promise<GpuContext> {
  try {
    return await requestNodeGpuOrFail(options, choice);
  } catch (e) {
    // requestGpu's message is the browser's advice; say what Node needs.
    if (e instanceof WebGpuUnavailableError && /no GPU adapter|navigator\.gpu/.test(e.message))
      throw new WebGpuUnavailableError(nodeGpuHelp());
    throw e;
  }
}

async function requestNodeGpuOrFail(options: RequestGpuOptions, choice: NodeAdapterChoice): Promise<GpuContext> {
  const { create } = await loadDawn();
  const userSetIcd = process.env.VK_ICD_FILENAMES !== undefined;
  if (choice === 'swiftshader' || (choice === 'auto' && !userSetIcd && !hasGpuDeviceNodes())) {
    useSwiftShader();
  }
  try {
    instance ??= create(dawnFlagsFromEnv());
    return await requestGpu(instance, options);
  } catch (e) {
    // No adapter from the system's drivers: fall back to SwiftShader, since the
    // Vulkan loader reads VK_ICD_FILENAMES again for each new instance.
    if (!(e instanceof WebGpuUnavailableError) || choice !== 'auto' || process.env.VK_ICD_FILENAMES === SWIFTSHADER_ICD) throw e;
    useSwiftShader();
    instance = create(dawnFlagsFromEnv());
    return requestGpu(instance, options);
  }
}
