// Explicit bind group layouts of buffer bindings, bind groups and storage
// buffers in a line each. Explicit layouts matter where several kernels share
// one WGSL file ('auto' layouts drop the bindings a kernel does not use);
// they come from the per-device cache (pipeline-cache.ts), so pipelines built
// on them are shared between instances.
import { bindGroupLayout } from './pipeline-cache.ts';

/** uniform, read-only storage, read-write storage. */
export type BindingKind = 'uniform' | 'read' | 'rw';

const TYPES: Record<BindingKind, GPUBufferBindingType> = { uniform: 'uniform', read: 'read-only-storage', rw: 'storage' };

/** Compute-stage buffer bindings firstBinding, firstBinding + 1, ... of the given kinds (shared per device). */
export function bufferLayout(device: GPUDevice, label: string, kinds: readonly BindingKind[], firstBinding = 0): GPUBindGroupLayout {
  return bindGroupLayout(
    device,
    label,
    kinds.map((k, i) => ({ binding: firstBinding + i, visibility: GPUShaderStage.COMPUTE, buffer: { type: TYPES[k] } })),
  );
}

export type Resource = GPUBuffer | GPUBufferBinding;

/** A bind group of buffers (or buffer bindings) at bindings firstBinding, firstBinding + 1, ... */
export function bindGroup(
  device: GPUDevice,
  label: string,
  layout: GPUBindGroupLayout,
  resources: readonly Resource[],
  firstBinding = 0,
): GPUBindGroup {
  return device.createBindGroup({
    label,
    layout,
    entries: resources.map((r, i) => ({ binding: firstBinding + i, resource: 'mapState' in r ? { buffer: r } : r })),
  });
}

/** A STORAGE buffer (plus `extraUsage`) of at least `bytes`, rounded up to 4, at least 4. */
export function storageBuffer(device: GPUDevice, label: string, bytes: number, extraUsage = 0): GPUBuffer {
  return device.createBuffer({ label, size: Math.max(4, Math.ceil(bytes / 4) * 4), usage: GPUBufferUsage.STORAGE | extraUsage });
}
