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

/** Copies `size` bytes at `offset` of `source` to the CPU (waits for the GPU). */
export async function readBuffer(device: GPUDevice, source: GPUBuffer, offset = 0, size = source.size - offset): Promise<ArrayBuffer> {
  const aligned = Math.ceil(size / 4) * 4;
  const staging = device.createBuffer({
    label: 'readBuffer.staging',
    size: Math.max(4, aligned),
    usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST,
  });
  try {
    const encoder = device.createCommandEncoder({ label: 'readBuffer' });
    if (aligned > 0) encoder.copyBufferToBuffer(source, offset, staging, 0, aligned);
    device.queue.submit([encoder.finish()]);
    await staging.mapAsync(GPUMapMode.READ);
    return staging.getMappedRange().slice(0, size);
  } finally {
    staging.destroy();
  }
}

export async function readU32(device: GPUDevice, source: GPUBuffer, offset = 0, count?: number): Promise<Uint32Array> {
  const n = count ?? (source.size - offset) / 4;
  return new Uint32Array(await readBuffer(device, source, offset, n * 4));
}

export async function readF32(device: GPUDevice, source: GPUBuffer, offset = 0, count?: number): Promise<Float32Array> {
  const n = count ?? (source.size - offset) / 4;
  return new Float32Array(await readBuffer(device, source, offset, n * 4));
}
