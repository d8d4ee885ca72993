// The one way every entry point (page, CLI, tests, benchmarks) gets a WebGPU
// device: the adapter's real limits, the optional features we use, and
// device loss / uncaptured errors routed to whoever shows them to the user.

/** Limits we raise to the adapter's maximum: the defaults (128 MiB bindings,
 * 16 KiB workgroup memory) are far below what volumes need. */
const RAISED_LIMITS = [
  'maxStorageBufferBindingSize',
  'maxBufferSize',
  'maxComputeWorkgroupStorageSize',
  'maxComputeInvocationsPerWorkgroup',
  'maxComputeWorkgroupSizeX',
  'maxComputeWorkgroupSizeY',
  'maxComputeWorkgroupSizeZ',
  'maxComputeWorkgroupsPerDimension',
  'maxStorageBuffersPerShaderStage',
  'maxUniformBufferBindingSize',
  'maxBindGroups',
  'maxBindingsPerBindGroup',
  'maxDynamicStorageBuffersPerPipelineLayout',
] as const;

/** Features used when present; nothing requires them. */
const WANTED_FEATURES: GPUFeatureName[] = ['timestamp-query', 'subgroups' as GPUFeatureName, 'indirect-first-instance', 'shader-f16'];

export interface AdapterSummary {
  vendor: string;
  architecture: string;
  device: string;
  description: string;
  /** True for CPU implementations (SwiftShader): figures are not GPU figures. */
  software: boolean;
}

export interface GpuFeatures {
  timestampQuery: boolean;
  subgroups: boolean;
  indirectFirstInstance: boolean;
  shaderF16: boolean;
}

export interface GpuContext {
  device: GPUDevice;
  adapter: AdapterSummary;
  features: GpuFeatures;
  /** Limits of the device as granted (equal to the adapter's for RAISED_LIMITS). */
  limits: GPUSupportedLimits;
  /** Resolves when the device is lost, with a readable reason. */
  lost: Promise<GpuFailure>;
}

export type GpuFailureKind = 'device-lost' | 'validation' | 'out-of-memory' | 'internal';

export interface GpuFailure {
  kind: GpuFailureKind;
  message: string;
}

/** Thrown when there is no usable WebGPU; the message says what to do. */
export class WebGpuUnavailableError extends Error {
  constructor(reason: string) {
    super(reason);
    this.name = 'WebGpuUnavailableError';
  }
}

export const BROWSER_HELP =
  'This page needs WebGPU. Use a current Chrome or Edge (113 or newer) or Safari 26; ' +
  'in Firefox enable dom.webgpu.enabled. On Linux, Chrome needs the flag ' +
  '--enable-unsafe-webgpu (and --enable-features=Vulkan). If WebGPU is enabled and this ' +
  'message remains, the GPU may be blocklisted: check chrome://gpu.';

export interface RequestGpuOptions {
  /** Called once per failure that happens after creation (loss, uncaptured error). */
  onFailure?: (failure: GpuFailure) => void;
  powerPreference?: GPUPowerPreference;
  label?: string;
  /**
   * 'adapter' (default): the adapter's limits. 'default': WebGPU's default
   * limits (128 MiB storage binding, 16 KiB workgroup storage, 256
   * invocations), like a laptop GPU; tests use it to exercise the fallbacks.
   */
  limits?: 'adapter' | 'default';
}

export function summarizeAdapter(info: GPUAdapterInfo | undefined): AdapterSummary {
  const vendor = info?.vendor ?? '';
  const architecture = info?.architecture ?? '';
  const device = info?.device ?? '';
  const description = info?.description ?? '';
  const all = `${vendor} ${architecture} ${device} ${description}`.toLowerCase();
  return {
    vendor,
    architecture,
    device,
    description,
    software: /swiftshader|llvmpipe|lavapipe|warp|software/.test(all),
  };
}

export function describeAdapter(a: AdapterSummary): string {
  const parts = [a.vendor, a.architecture, a.device, a.description].filter((s) => s.length > 0);
  const unique = parts.filter((p, i) => parts.indexOf(p) === i);
  return (unique.join(' / ') || 'unknown adapter') + (a.software ? ' (software rasterizer, not a GPU)' : '');
}

/** Requests an adapter and a device with raised limits and wanted features. */
export async function requestGpu(gpu: GPU | undefined, options: RequestGpuOptions = {}): Promise<GpuContext> {
  if (!gpu) throw new WebGpuUnavailableError(`WebGPU is not available (navigator.gpu is missing). ${BROWSER_HELP}`);
  const adapter = await gpu.requestAdapter({ powerPreference: options.powerPreference ?? 'high-performance' });
  if (!adapter) throw new WebGpuUnavailableError(`WebGPU is present but no GPU adapter was found. ${BROWSER_HELP}`);

  const requiredLimits: Record<string, number> = {};
  for (const name of options.limits === 'default' ? [] : RAISED_LIMITS) {
    const value = (adapter.limits as unknown as Record<string, number | undefined>)[name];
    if (typeof value === 'number') requiredLimits[name] = value;
  }
  const requiredFeatures = WANTED_FEATURES.filter((f) => adapter.features.has(f));
  const device = await adapter.requestDevice({
    label: options.label ?? 'zfpiso.device',
    requiredLimits,
    requiredFeatures,
  });

  const report = options.onFailure ?? (() => undefined);
  device.addEventListener('uncapturederror', (event) => {
    const error = (event as GPUUncapturedErrorEvent).error;
    report({ kind: classifyError(error), message: error.message });
  });
  const lost = device.lost.then((info) => {
    const failure: GpuFailure = {
      kind: 'device-lost',
      message:
        info.reason === 'destroyed'
          ? 'The WebGPU device was destroyed.'
          : `The GPU device was lost${info.message ? `: ${info.message}` : ''}. ` +
            'This can happen after a driver reset or when the GPU runs out of memory; reload the page to continue.',
    };
    if (info.reason !== 'destroyed') report(failure);
    return failure;
  });

  return {
    device,
    adapter: summarizeAdapter(adapter.info),
    features: {
      timestampQuery: device.features.has('timestamp-query'),
      subgroups: device.features.has('subgroups'),
      indirectFirstInstance: device.features.has('indirect-first-instance'),
      shaderF16: device.features.has('shader-f16'),
    },
    limits: device.limits,
    lost,
  };
}

export function classifyError(error: GPUError): GpuFailureKind {
  if (typeof GPUValidationError !== 'undefined' && error instanceof GPUValidationError) return 'validation';
  if (typeof GPUOutOfMemoryError !== 'undefined' && error instanceof GPUOutOfMemoryError) return 'out-of-memory';
  const name = error.constructor?.name ?? '';
  if (name.includes('Validation')) return 'validation';
  if (name.includes('OutOfMemory')) return 'out-of-memory';
  return 'internal';
}

/** Plain-data view of the limits for JSON output. */
export function limitsToObject(limits: GPUSupportedLimits): Record<string, number> {
  const out: Record<string, number> = {};
  // GPUSupportedLimits exposes its values as prototype getters.
  let proto: object | null = limits;
  while (proto && proto !== Object.prototype) {
    for (const key of Object.getOwnPropertyNames(proto)) {
      if (key === 'constructor') continue;
      const value = (limits as unknown as Record<string, unknown>)[key];
      if (typeof value === 'number') out[key] = value;
    }
    proto = Object.getPrototypeOf(proto);
  }
  return Object.fromEntries(Object.entries(out).sort(([a], [b]) => a.localeCompare(b)));
}
