// Small helpers for the isosurface classes: explicit bind group layouts
// (several kernels share one WGSL file, so 'auto' layouts would drop the
// bindings a kernel does not use), pipelines, bind groups.
import { createComputePipeline, type WgslPart } from '../gpu/wgsl.ts';

/** uniform, read-only storage, read-write storage. */
export type BindingKind = 'uniform' | 'read' | 'rw';

const TYPES: Record<BindingKind, GPUBufferBindingType> = { uniform: 'uniform', read: 'read-only-storage', rw: 'storage' };

/** Bindings firstBinding, firstBinding + 1, ... of the given kinds. */
export function bindGroupLayout(device: GPUDevice, label: string, kinds: BindingKind[], firstBinding = 0): GPUBindGroupLayout {
  return device.createBindGroupLayout({
    label,
    entries: kinds.map((k, i) => ({ binding: firstBinding + i, visibility: GPUShaderStage.COMPUTE, buffer: { type: TYPES[k] } })),
  });
}

export function computePipeline(
  device: GPUDevice,
  label: string,
  parts: WgslPart[],
  entryPoint: string,
  layouts: GPUBindGroupLayout[],
  constants?: Record<string, number>,
): Promise<GPUComputePipeline> {
  return createComputePipeline(device, label, parts, entryPoint, {
    layout: device.createPipelineLayout({ label, bindGroupLayouts: layouts }),
    constants,
  });
}

export type Resource = GPUBuffer | GPUBufferBinding;

export function bindGroup(device: GPUDevice, label: string, layout: GPUBindGroupLayout, resources: Resource[], firstBinding = 0): GPUBindGroup {
  return device.createBindGroup({
    label,
    layout,
    entries: resources.map((r, i) => ({ binding: firstBinding + i, resource: 'mapState' in r ? { buffer: r } : r })),
  });
}

export function storageBuffer(device: GPUDevice, label: string, bytes: number, extraUsage = 0): GPUBuffer {
  return device.createBuffer({ label, size: Math.max(4, Math.ceil(bytes / 4) * 4), usage: GPUBufferUsage.STORAGE | extraUsage });
}
