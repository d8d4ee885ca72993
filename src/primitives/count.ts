// GPU-side element counts. Every primitive takes its count either as a
// `GpuCount` (a u32 written by an earlier dispatch, never read back) or, for
// convenience and tests, as a host number.
//
// Counts enter a primitive by `copyBufferToBuffer` into its own parameter
// buffer, so they are ordered with the rest of the command encoder (a kernel
// earlier in the same encoder may write them) and the caller's count buffer
// needs only COPY_SRC usage.

import type { GpuCount } from '../gpu/buffer-ref.ts';
import { baseDevice } from '../gpu/memory-meter.ts';

/** A count on the GPU, or a host number (written to a small ring of slots). */
export type CountLike = GpuCount | number;

/** Slots in each device's host-count ring: at most this many host-number
 * encodes may be recorded between two queue submissions. */
export const HOST_COUNT_SLOTS = 4096;

/**
 * Host numbers become GPU counts through `queue.writeBuffer` into a ring of
 * slots. writeBuffer is ordered on the queue, not in the encoder, so each
 * encode takes its own slot; a slot is reused only after HOST_COUNT_SLOTS more
 * host counts, by which time the encoder that read it has been submitted.
 */
class HostCountRing {
  readonly buffer: GPUBuffer;
  private next = 0;
  private readonly word = new Uint32Array(1);

  constructor(private readonly device: GPUDevice) {
    this.buffer = device.createBuffer({
      label: 'primitives.hostCounts',
      size: HOST_COUNT_SLOTS * 4,
      // STORAGE: IndirectArgs reads counts through a storage binding
      usage: GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST | GPUBufferUsage.STORAGE,
    });
  }

  slot(value: number): GpuCount {
    const offset = this.next * 4;
    this.next = (this.next + 1) % HOST_COUNT_SLOTS;
    this.word[0] = value;
    this.device.queue.writeBuffer(this.buffer, offset, this.word);
    return { buffer: this.buffer, offset };
  }
}

const rings = new WeakMap<GPUDevice, HostCountRing>();

/** A GpuCount for `count`: itself, or a host-count slot holding the number. */
export function toGpuCount(device: GPUDevice, count: CountLike): GpuCount {
  if (typeof count !== 'number') {
    if (count.offset % 4 !== 0) throw new RangeError(`GpuCount offset ${count.offset} is not a multiple of 4`);
    return count;
  }
  if (!Number.isInteger(count) || count < 0 || count > 0xffffffff) throw new RangeError(`count ${count} is not a u32`);
  // one ring per device, shared by its metered views (it outlives any of them)
  const base = baseDevice(device);
  let ring = rings.get(base);
  if (!ring) {
    ring = new HostCountRing(base);
    rings.set(base, ring);
  }
  return ring.slot(count);
}

/** Records a copy of the count's u32 into `dst` at byte `dstOffset`. */
export function encodeCountCopy(device: GPUDevice, encoder: GPUCommandEncoder, count: CountLike, dst: GPUBuffer, dstOffset: number): void {
  const c = toGpuCount(device, count);
  encoder.copyBufferToBuffer(c.buffer, c.offset, dst, dstOffset, 4);
}
