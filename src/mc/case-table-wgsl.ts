// WGSL side of the marching-cubes conventions: helpers a kernel composes in, and
// the packed table it binds (2 KiB: a read-only storage buffer of 512 u32, or a
// uniform buffer read as array<vec4<u32>, 128>).
import caseTableWgsl from '../../shaders/mc/case_table.wgsl?raw';
import type { WgslPart } from '../gpu/wgsl.ts';
import { packCaseTable } from './case-table.ts';

export const mcCaseTableSnippet: WgslPart = { name: 'shaders/mc/case_table.wgsl', code: caseTableWgsl };

/** A buffer holding packCaseTable(); usage defaults to STORAGE (add UNIFORM to bind it as one). */
export function createCaseTableBuffer(device: GPUDevice, usage: GPUBufferUsageFlags = GPUBufferUsage.STORAGE): GPUBuffer {
  const data = packCaseTable();
  const buffer = device.createBuffer({ label: 'mc.caseTable', size: data.byteLength, usage, mappedAtCreation: true });
  new Uint32Array(buffer.getMappedRange()).set(data);
  buffer.unmap();
  return buffer;
}
