// Counts GPU memory from outside the code under test: the device's
// createBuffer wrapped (on the instance), each buffer's size added when made
// and taken off once when destroyed. What the product reports about its own
// GPU memory (src/gpu/memory-meter.ts) is checked against this.
export interface BufferCount {
  /** Bytes of buffers made since the wrapper and not destroyed. */
  readonly live: number;
  /** The most `live` has been since the last resetPeak. */
  readonly peak: number;
  resetPeak(): void;
  /** Called after every allocation with the live bytes (e.g. to check a bound at every step). */
  onAllocate?: (live: number) => void;
  /** Puts the device's createBuffer back. */
  restore(): void;
}

export function countBuffers(device: GPUDevice): BufferCount {
  const original = device.createBuffer;
  const count = {
    live: 0,
    peak: 0,
    onAllocate: undefined as ((live: number) => void) | undefined,
    resetPeak() {
      count.peak = count.live;
    },
    restore() {
      Object.defineProperty(device, 'createBuffer', { configurable: true, writable: true, value: original });
    },
  };
  Object.defineProperty(device, 'createBuffer', {
    configurable: true,
    writable: true,
    value(descriptor: GPUBufferDescriptor) {
      const buffer = original.call(device, descriptor);
      const size = buffer.size;
      count.live += size;
      if (count.live > count.peak) count.peak = count.live;
      const destroy = buffer.destroy;
      let live = true;
      Object.defineProperty(buffer, 'destroy', {
        configurable: true,
        value() {
          if (live) {
            live = false;
            count.live -= size;
          }
          return destroy.call(buffer);
        },
      });
      count.onAllocate?.(count.live);
      return buffer;
    },
  });
  return count;
}
