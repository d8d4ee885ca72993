// GPU memory counted where it is made: `meteredGpu(gpu)` gives a view of
// the device whose createBuffer adds each buffer's size to a meter and whose
// buffers take it off again when destroyed (once). Everything built on the
// view (a store's pools, its surfaces with their scratch, staging and
// uniforms) is counted, so "what does this hold on the GPU" is an
// observation, not an estimate kept in step with the code by hand.
// Per-device caches (pipelines, layouts, the shared count ring) key on the
// device itself (`baseDevice`), so a view compiles nothing new, and what
// they hold outlives any one view and is not counted in it.
import type { GpuContext } from './device.ts';

const BASE = Symbol('zfpiso.baseDevice');

export class GpuMemoryMeter {
  /** Bytes of the buffers made through the view and not destroyed. */
  bytes = 0;
  /** The most `bytes` has been (since resetPeak). */
  peak = 0;
  /** Live buffers. */
  buffers = 0;
  /** Called after every allocation with the new total (tests check bounds there). */
  onAllocate?: (bytes: number) => void;

  /**
   * `parent`: a meter that counts this one's buffers too (a page's budget
   * counts every store's; each store's own meter says what it holds).
   */
  constructor(readonly parent?: GpuMemoryMeter) {}

  add(size: number): void {
    this.bytes += size;
    this.buffers++;
    if (this.bytes > this.peak) this.peak = this.bytes;
    this.onAllocate?.(this.bytes);
    this.parent?.add(size);
  }

  remove(size: number): void {
    this.bytes -= size;
    this.buffers--;
    this.parent?.remove(size);
  }

  /** The peak from now on starts at what is held now. */
  resetPeak(): void {
    this.peak = this.bytes;
  }
}

/** The device a view was made from (the device itself for a plain one): the key of per-device caches. */
export function baseDevice(device: GPUDevice): GPUDevice {
  return (device as unknown as { [BASE]?: GPUDevice })[BASE] ?? device;
}

/** Counts `buffer` in `meter` until it is destroyed. */
export function meterBuffer(meter: GpuMemoryMeter, buffer: GPUBuffer): GPUBuffer {
  const size = buffer.size;
  meter.add(size);
  const destroy = buffer.destroy;
  let live = true;
  Object.defineProperty(buffer, 'destroy', {
    configurable: true,
    value() {
      if (live) {
        live = false;
        meter.remove(size);
      }
      return destroy.call(buffer);
    },
  });
  return buffer;
}

/** A view of `device` whose buffers are counted in `meter`; everything else is the device's own. */
export function meteredDevice(device: GPUDevice, meter: GpuMemoryMeter): GPUDevice {
  const base = baseDevice(device);
  const bound = new Map<PropertyKey, unknown>();
  const createBuffer = (descriptor: GPUBufferDescriptor) => meterBuffer(meter, device.createBuffer(descriptor));
  return new Proxy(base, {
    get(target, prop) {
      if (prop === BASE) return base;
      if (prop === 'createBuffer') return createBuffer;
      const value = Reflect.get(target, prop, target);
      if (typeof value !== 'function') return value;
      let fn = bound.get(prop);
      if (!fn) {
        fn = (value as (...a: unknown[]) => unknown).bind(target);
        bound.set(prop, fn);
      }
      return fn;
    },
  });
}

/** The context with its device replaced by a metered view, and the meter. */
export function meteredGpu(gpu: GpuContext, meter = new GpuMemoryMeter()): { gpu: GpuContext; meter: GpuMemoryMeter } {
  return { gpu: { ...gpu, device: meteredDevice(gpu.device, meter) }, meter };
}
