// References to GPU data that the modules pass each other: a u32 count
// written on the GPU, a buffer or a range of one, and where work is recorded
// (the caller's command encoder or compute pass).

/** A u32 at byte `offset` (a multiple of 4) of `buffer`, typically written by an earlier GPU pass and never read back. */
export interface GpuCount {
  buffer: GPUBuffer;
  offset: number;
}

/** A whole buffer, or a range of one (a storage binding's offset must be a multiple of minStorageBufferOffsetAlignment). */
export type GpuBufferRef = GPUBuffer | { buffer: GPUBuffer; offset?: number; size?: number };

/** Where work is recorded: the caller's command encoder (a pass is opened) or compute pass. */
export type ComputeTarget = GPUCommandEncoder | GPUComputePassEncoder;

function isBuffer(ref: GpuBufferRef): ref is GPUBuffer {
  return 'mapState' in ref;
}

/** The reference as a bind group entry's resource. */
export function binding(ref: GpuBufferRef): GPUBufferBinding {
  if (isBuffer(ref)) return { buffer: ref };
  const b: GPUBufferBinding = { buffer: ref.buffer, offset: ref.offset ?? 0 };
  if (ref.size !== undefined) b.size = ref.size;
  return b;
}

export function refBuffer(ref: GpuBufferRef): GPUBuffer {
  return isBuffer(ref) ? ref : ref.buffer;
}

export function refOffset(ref: GpuBufferRef): number {
  return isBuffer(ref) ? 0 : (ref.offset ?? 0);
}

/** The bound size, or -1 for "to the end of the buffer" (a cache key). */
export function refBoundSize(ref: GpuBufferRef): number {
  return isBuffer(ref) ? -1 : (ref.size ?? -1);
}

/** Bytes visible through the reference. */
export function refSize(ref: GpuBufferRef): number {
  if (isBuffer(ref)) return ref.size;
  return ref.size ?? ref.buffer.size - (ref.offset ?? 0);
}

export function isCommandEncoder(t: ComputeTarget): t is GPUCommandEncoder {
  return typeof (t as GPUCommandEncoder).beginComputePass === 'function';
}

/** Runs `record` in `target` if it is a pass, else in a new pass of the command encoder. */
export function inPass(
  target: ComputeTarget,
  label: string,
  record: (pass: GPUComputePassEncoder) => void,
  timestampWrites?: GPUComputePassTimestampWrites,
): void {
  if (!isCommandEncoder(target)) {
    record(target);
    return;
  }
  const desc: GPUComputePassDescriptor = { label };
  if (timestampWrites) desc.timestampWrites = timestampWrites;
  const pass = target.beginComputePass(desc);
  record(pass);
  pass.end();
}
