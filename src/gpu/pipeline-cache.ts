// The per-device pipeline cache: every compute pipeline of the project comes
// from here, so a second Isosurface, decoder or scan on the same device
// compiles nothing. Per device (a WeakMap: the cache goes with the device):
//   shader modules      by their composed WGSL source
//   compute pipelines   by module, entry point, override constants and layout
//   bind group layouts  by their entries (bindGroupLayout), so explicit
//                       layouts are the same objects in every instance and
//                       pipelines built on them are shared too
//   pipeline layouts    by their bind group layouts
// Keys are built when a pipeline is asked for (creation time), never while
// recording. Concurrent requests share one promise; a failed compilation is
// forgotten, so a later request tries again. A shared pipeline keeps the label
// of its first request.
import { baseDevice } from './memory-meter.ts';
import { composeWgsl, createShaderModule, type WgslPart } from './wgsl.ts';

export interface ComputePipelineOptions {
  /**
   * 'auto' (default; bind groups then come from pipeline.getBindGroupLayout),
   * the bind group layouts in group order (best from bindGroupLayout(), which
   * shares them per device), or a pipeline layout (shared only with requests
   * passing the same object).
   */
  layout?: 'auto' | readonly GPUBindGroupLayout[] | GPUPipelineLayout;
  /** Values of the WGSL `override` constants. */
  constants?: Record<string, number>;
}

class DeviceCache {
  readonly modules = new Map<string, { id: number; module: Promise<GPUShaderModule> }>();
  readonly pipelines = new Map<string, Promise<GPUComputePipeline>>();
  readonly layouts = new Map<string, GPUBindGroupLayout>();
  readonly pipelineLayouts = new Map<string, GPUPipelineLayout>();
  private readonly ids = new WeakMap<object, number>();
  private nextId = 1;
  private nextModule = 1;

  moduleId(): number {
    return this.nextModule++;
  }

  /** A number per object (layouts), for keys. */
  id(o: object): number {
    let id = this.ids.get(o);
    if (id === undefined) {
      id = this.nextId++;
      this.ids.set(o, id);
    }
    return id;
  }
}

const caches = new WeakMap<GPUDevice, DeviceCache>();

function cacheOf(device: GPUDevice): DeviceCache {
  const base = baseDevice(device); // a metered view shares its device's cache
  let c = caches.get(base);
  if (!c) {
    c = new DeviceCache();
    caches.set(base, c);
  }
  return c;
}

/** Stable text of a descriptor (object keys sorted), for keys. */
function canonical(v: unknown): string {
  if (Array.isArray(v)) return `[${v.map(canonical).join(',')}]`;
  if (v !== null && typeof v === 'object') {
    return `{${Object.keys(v)
      .sort()
      .filter((k) => (v as Record<string, unknown>)[k] !== undefined)
      .map((k) => `${k}:${canonical((v as Record<string, unknown>)[k])}`)
      .join(',')}}`;
  }
  return String(v);
}

/** The device's bind group layout with these entries (created once per device; `label` from the first request). */
export function bindGroupLayout(device: GPUDevice, label: string, entries: readonly GPUBindGroupLayoutEntry[]): GPUBindGroupLayout {
  const cache = cacheOf(device);
  const key = canonical(entries);
  let layout = cache.layouts.get(key);
  if (!layout) {
    layout = device.createBindGroupLayout({ label, entries: [...entries] });
    cache.layouts.set(key, layout);
  }
  return layout;
}

function pipelineLayout(device: GPUDevice, cache: DeviceCache, label: string, groups: readonly GPUBindGroupLayout[]): GPUPipelineLayout {
  const key = groups.map((g) => cache.id(g)).join('.');
  let layout = cache.pipelineLayouts.get(key);
  if (!layout) {
    layout = device.createPipelineLayout({ label, bindGroupLayouts: [...groups] });
    cache.pipelineLayouts.set(key, layout);
  }
  return layout;
}

function shaderModule(
  device: GPUDevice,
  cache: DeviceCache,
  label: string,
  parts: WgslPart[],
): { id: number; module: Promise<GPUShaderModule> } {
  const code = composeWgsl(...parts);
  let entry = cache.modules.get(code);
  if (!entry) {
    const module = createShaderModule(device, label, parts, code);
    entry = { id: cache.moduleId(), module };
    cache.modules.set(code, entry);
    module.catch(() => cache.modules.delete(code));
  }
  return entry;
}

/**
 * The compute pipeline of `entryPoint` in the WGSL composed of `parts`, with
 * these constants and layout: compiled once per device, then shared.
 * Rejects with WgslCompileError (messages mapped to the snippet files).
 */
export function createComputePipeline(
  device: GPUDevice,
  label: string,
  parts: WgslPart[],
  entryPoint: string,
  options: ComputePipelineOptions = {},
): Promise<GPUComputePipeline> {
  const cache = cacheOf(device);
  const { id, module } = shaderModule(device, cache, label, parts);
  const spec = options.layout ?? 'auto';
  let layout: GPUPipelineLayout | 'auto';
  let layoutKey: string;
  if (spec === 'auto') {
    layout = 'auto';
    layoutKey = 'auto';
  } else if (Array.isArray(spec)) {
    layout = pipelineLayout(device, cache, label, spec as readonly GPUBindGroupLayout[]);
    layoutKey = `g${cache.id(layout)}`;
  } else {
    layout = spec as GPUPipelineLayout;
    layoutKey = `p${cache.id(layout)}`;
  }
  const constants = options.constants ?? {};
  const constantsKey = Object.keys(constants)
    .sort()
    .map((k) => `${k}=${constants[k]}`)
    .join(',');
  const key = `${id}|${entryPoint}|${constantsKey}|${layoutKey}`;
  let pipeline = cache.pipelines.get(key);
  if (!pipeline) {
    pipeline = module.then((m) => device.createComputePipelineAsync({ label, layout, compute: { module: m, entryPoint, constants } }));
    cache.pipelines.set(key, pipeline);
    pipeline.catch(() => cache.pipelines.delete(key));
  }
  return pipeline;
}

/** Modules and pipelines cached for `device` (tests, benchmarks). */
export function pipelineCacheSize(device: GPUDevice): { modules: number; pipelines: number; bindGroupLayouts: number } {
  const c = caches.get(device);
  return { modules: c?.modules.size ?? 0, pipelines: c?.pipelines.size ?? 0, bindGroupLayouts: c?.layouts.size ?? 0 };
}
