// One object per device (shared by its metered views: src/gpu/memory-meter.ts),
// made on first use; a failed make is tried again by the next call.
import { baseDevice } from './memory-meter.ts';

export function perDevice<T>(make: (device: GPUDevice) => Promise<T>): (device: GPUDevice) => Promise<T> {
  const made = new WeakMap<GPUDevice, Promise<T>>();
  return (device) => {
    const base = baseDevice(device);
    let p = made.get(base);
    if (!p) {
      p = make(base);
      p.catch(() => made.delete(base));
      made.set(base, p);
    }
    return p;
  };
}
