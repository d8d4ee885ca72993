// readBuffer: a readback through one staging buffer of at most
// READ_PIECE_BYTES, reused piece by piece, returns the bytes uploaded
// (random data of awkward sizes around the piece), at any 4-byte offset,
// and makes no staging buffer larger than the piece (what a stream's budget
// keeps free for short-lived buffers).
import { describe, expect } from 'vitest';
import { createBuffer, READ_PIECE_BYTES, readBuffer } from '../../../src/gpu/buffers.ts';
import { GpuMemoryMeter, meteredGpu } from '../../../src/gpu/memory-meter.ts';
import { gpuTest } from '../../helpers/gpu.ts';

function randomBytes(n: number, seed: number): Uint8Array {
  const out = new Uint8Array(n);
  let s = seed >>> 0 || 1;
  for (let i = 0; i < n; i++) {
    s ^= s << 13;
    s ^= s >>> 17;
    s ^= s << 5;
    out[i] = s & 255;
  }
  return out;
}

describe('readBuffer', () => {
  gpuTest('returns the uploaded bytes at awkward sizes and offsets, through staging no larger than a piece', async ({ gpu }) => {
    const P = READ_PIECE_BYTES;
    const meter = new GpuMemoryMeter();
    const view = meteredGpu(gpu, meter).gpu;
    let before = 0;
    let largest = 0;
    meter.onAllocate = () => {
      largest = Math.max(largest, meter.bytes - before);
    };
    for (const [total, offset, size] of [
      [4, 0, 0],
      [4, 0, 1],
      [64, 4, 57],
      [P, 0, P],
      [P + 4, 0, P + 4],
      [3 * P + 100, 8, 3 * P + 92],
      [2 * P, P, P - 3],
    ]) {
      const data = randomBytes(total, total + offset + size);
      const source = createBuffer(gpu.device, 'source', total, GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC, data);
      before = meter.bytes;
      largest = 0;
      const got = new Uint8Array(await readBuffer(view.device, source, offset, size));
      expect(got.length).toBe(size);
      const want = data.subarray(offset, offset + size);
      expect(
        got.every((b, i) => b === want[i]),
        `${total} ${offset} ${size}`,
      ).toBe(true);
      // the staging buffer is counted (the metered device made it; none for nothing to read) and no larger than a piece
      expect(largest > 0).toBe(size > 0);
      expect(largest).toBeLessThanOrEqual(P);
      source.destroy();
    }
    expect(meter.bytes).toBe(0);
  });
});
