// The isosurface WGSL files (shaders/isosurface/) and what each kernel is
// composed of.
import commonWgsl from '../../shaders/isosurface/common.wgsl?raw';
import activeBlocksWgsl from '../../shaders/isosurface/active_blocks.wgsl?raw';
import activeGroupsWgsl from '../../shaders/isosurface/active_groups.wgsl?raw';
import lruWgsl from '../../shaders/isosurface/lru.wgsl?raw';
import planWgsl from '../../shaders/isosurface/plan.wgsl?raw';
import blockMcCommonWgsl from '../../shaders/isosurface/block_mc_common.wgsl?raw';
import blockClassifyWgsl from '../../shaders/isosurface/block_classify.wgsl?raw';
import blockExpandWgsl from '../../shaders/isosurface/block_expand.wgsl?raw';
import blockEmitWgsl from '../../shaders/isosurface/block_emit.wgsl?raw';
import vertexFormatWgsl from '../../shaders/isosurface/vertex_format.wgsl?raw';
import edgeOwnerWgsl from '../../shaders/isosurface/edge_owner.wgsl?raw';
import blocksStreamWgsl from '../../shaders/isosurface/blocks_stream.wgsl?raw';
import blocksPoolWgsl from '../../shaders/isosurface/blocks_pool.wgsl?raw';
import slotRangesWgsl from '../../shaders/isosurface/slot_ranges.wgsl?raw';
import type { WgslPart } from '../gpu/wgsl.ts';
import { mcCaseTableSnippet } from '../mc/case-table-wgsl.ts';
import { gridSnippet } from '../gpu/dispatch.ts';

const part = (name: string, code: string): WgslPart => ({ name: `shaders/isosurface/${name}.wgsl`, code });

/**
 * The compressed vertex format: `decode_vertex_position(w0, w1, grid) -> vec3f`
 * (voxel index space) and `encode_vertex_edge`. The renderer composes this
 * part into its vertex shader.
 */
export const vertexFormatSnippet = part('vertex_format', vertexFormatWgsl);
export const isosurfaceCommonSnippet = part('common', commonWgsl);

/** How kernels name blocks (block-ids.ts): a stream's raster ids, a pool's slot-relative ids. Composed after a kernel's parts. */
export const blockIdsSnippet = {
  stream: part('blocks_stream', blocksStreamWgsl),
  pool: part('blocks_pool', blocksPoolWgsl),
};

const base = [gridSnippet, isosurfaceCommonSnippet];
const edgeOwner = part('edge_owner', edgeOwnerWgsl);

export const isosurfaceWgsl = {
  activeBlocks: [...base, part('active_blocks', activeBlocksWgsl)],
  activeGroups: [...base, part('active_groups', activeGroupsWgsl)],
  lru: [...base, part('lru', lruWgsl)],
  plan: [...base, part('plan', planWgsl)],
  blockClassify: [
    ...base,
    mcCaseTableSnippet,
    edgeOwner,
    part('block_mc_common', blockMcCommonWgsl),
    part('block_classify', blockClassifyWgsl),
  ],
  blockExpand: [...base, mcCaseTableSnippet, edgeOwner, part('block_expand', blockExpandWgsl)],
  blockEmit: [
    ...base,
    mcCaseTableSnippet,
    vertexFormatSnippet,
    edgeOwner,
    part('block_mc_common', blockMcCommonWgsl),
    part('block_emit', blockEmitWgsl),
  ],
  slotRanges: [part('slot_ranges', slotRangesWgsl)],
} satisfies Record<string, WgslPart[]>;
