// Dispatch grids: `workgroups` linear workgroups laid out as (x, 1, 1), then
// (x, y, 1) past the per-dimension limit, (x, y, z) past its square. The one
// WGSL side is shaders/common/grid.wgsl (`dispatch_grid` writes the same grid
// on the GPU for indirect dispatches; kernels rebuild their linear index with
// `grid_workgroup_index` / `grid_invocation_index`); `dispatchGrid` is its
// host twin, for direct dispatches.

import gridWgsl from '../../shaders/common/grid.wgsl?raw';
import type { WgslPart } from './wgsl.ts';

/** ceil_div, dispatch_grid (override MAX_WG_PER_DIM), grid_workgroup_index, grid_invocation_index. */
export const gridSnippet: WgslPart = { name: 'shaders/common/grid.wgsl', code: gridWgsl };

/** WebGPU's default maxComputeWorkgroupsPerDimension (valid on every device). */
export const DEFAULT_MAX_WORKGROUPS_PER_DIMENSION = 65535;

/**
 * [x, y, z] covering `workgroups` (x * y * z >= workgroups), exactly as
 * dispatch_grid in grid.wgsl (z exceeds the limit only past limit^3, which no
 * device can dispatch).
 */
export function dispatchGrid(workgroups: number, maxPerDimension = DEFAULT_MAX_WORKGROUPS_PER_DIMENSION): [number, number, number] {
  if (workgroups <= 0) return [0, 1, 1];
  if (workgroups <= maxPerDimension) return [workgroups, 1, 1];
  const z = Math.ceil(workgroups / (maxPerDimension * maxPerDimension));
  const rest = Math.ceil(workgroups / z);
  const y = Math.ceil(rest / maxPerDimension);
  return [Math.ceil(rest / y), y, z];
}

/** Records a direct dispatch of `workgroups` linear workgroups (nothing for 0). */
export function dispatchWorkgroups(
  pass: GPUComputePassEncoder,
  workgroups: number,
  maxPerDimension = DEFAULT_MAX_WORKGROUPS_PER_DIMENSION,
): void {
  if (workgroups <= 0) return;
  if (workgroups <= maxPerDimension) {
    pass.dispatchWorkgroups(workgroups);
    return;
  }
  const [x, y, z] = dispatchGrid(workgroups, maxPerDimension);
  pass.dispatchWorkgroups(x, y, z);
}
