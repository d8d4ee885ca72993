// Small buffer helpers. `readBuffer` maps a copy and waits: for tests, the CLI
// and load-time work, never for the per-isovalue path.

export function createBuffer(
  device: GPUDevice,
  label: string,
  size: number,
  usage: GPUBufferUsageFlags,
  data?: ArrayBufferView,
): GPUBuffer {
  // Buffers must be a multiple of 4 bytes when mapped at creation.
  const byteSize = Math.max(4, Math.ceil(Math.max(size, data?.byteLength ?? 0) / 4) * 4);
  const buffer = device.createBuffer({ label, size: byteSize, usage, mappedAtCreation: data !== undefined });
  if (data) {
    new Uint8Array(buffer.getMappedRange()).set(new Uint8Array(data.buffer, data.byteOffset, data.byteLength));
    buffer.unmap();
  }
  return buffer;
}

/**
 * Copies `size` bytes at `offset` of `source` to the CPU (waits for the GPU),
 * through one staging buffer of at most READ_PIECE_BYTES reused piece by
 * piece: a readback of a large surface (the CLI's meshes) then fits in what
 * a stream's budget keeps free for short-lived buffers.
 */
export async function readBuffer(device: GPUDevice, source: GPUBuffer, offset = 0, size = source.size - offset): Promise<ArrayBuffer> {
  const aligned = Math.ceil(size / 4) * 4;
  if (aligned === 0) return new ArrayBuffer(0);
  const piece = Math.min(aligned, READ_PIECE_BYTES);
  const staging = device.createBuffer({
    label: 'readBuffer.staging',
    size: piece,
    usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST,
  });
  const out = new Uint8Array(aligned);
  try {
    for (let at = 0; at < aligned; at += piece) {
      const n = Math.min(piece, aligned - at);
      const encoder = device.createCommandEncoder({ label: 'readBuffer' });
      encoder.copyBufferToBuffer(source, offset + at, staging, 0, n);
      device.queue.submit([encoder.finish()]);
      await staging.mapAsync(GPUMapMode.READ, 0, n);
      out.set(new Uint8Array(staging.getMappedRange(0, n)), at);
      staging.unmap();
    }
    return out.buffer.slice(0, size);
  } finally {
    staging.destroy();
  }
}

/** The largest staging buffer a readback makes (a quarter of the stream's reserve for short-lived buffers). */
export const READ_PIECE_BYTES = 256 << 10;

export async function readU32(device: GPUDevice, source: GPUBuffer, offset = 0, count?: number): Promise<Uint32Array> {
  const n = count ?? (source.size - offset) / 4;
  return new Uint32Array(await readBuffer(device, source, offset, n * 4));
}

export async function readF32(device: GPUDevice, source: GPUBuffer, offset = 0, count?: number): Promise<Float32Array> {
  const n = count ?? (source.size - offset) / 4;
  return new Float32Array(await readBuffer(device, source, offset, n * 4));
}
