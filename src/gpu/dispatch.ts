// Dispatch sizes above the 65535-workgroups-per-dimension limit are laid out
// as a 2D grid; kernels rebuild the linear workgroup index with
// `linear_workgroup_index` from shaders/common/grid.wgsl.

import gridWgsl from '../../shaders/common/grid.wgsl?raw';
import type { WgslPart } from './wgsl.ts';

export const gridSnippet: WgslPart = { name: 'shaders/common/grid.wgsl', code: gridWgsl };

/** [x, y] workgroup counts covering `workgroups` (x * y >= workgroups). */
export function grid2d(workgroups: number, maxPerDimension = 65535): [number, number] {
  if (workgroups <= 0) return [0, 1];
  if (workgroups <= maxPerDimension) return [workgroups, 1];
  const y = Math.ceil(workgroups / maxPerDimension);
  if (y > maxPerDimension) throw new Error(`dispatch of ${workgroups} workgroups exceeds ${maxPerDimension}^2`);
  return [Math.ceil(workgroups / y), y];
}

/** Records a direct dispatch of `workgroups` linear workgroups as a 2D grid. */
export function dispatchLinear(pass: GPUComputePassEncoder, workgroups: number, maxPerDimension = 65535): void {
  const [x, y] = grid2d(workgroups, maxPerDimension);
  if (x > 0) pass.dispatchWorkgroups(x, y);
}
