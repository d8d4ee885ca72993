// The chunk-pool WGSL (shaders/store/) composed with the zfp decode core.
import { gridSnippet } from '../gpu/dispatch.ts';
import type { WgslPart } from '../gpu/wgsl.ts';
import { zfpDecodeCore } from '../zfp/wgsl.ts';
import chunkParams from '../../shaders/store/chunk_params.wgsl?raw';
import chunkBlocks from '../../shaders/store/chunk_blocks.wgsl?raw';
import chunkRanges from '../../shaders/store/chunk_ranges.wgsl?raw';
import chunkNeighbourhood from '../../shaders/store/chunk_neighbourhood.wgsl?raw';

const part = (name: string, code: string): WgslPart => ({ name: `shaders/store/${name}.wgsl`, code });

/** The decode core with the pool's block addressing (block_start) instead of a stream's. */
const pooledDecoder = [gridSnippet, zfpDecodeCore.u64, zfpDecodeCore.stream, part('chunk_params', chunkParams), part('chunk_blocks', chunkBlocks), zfpDecodeCore.codec, zfpDecodeCore.decodeBlock];

export const chunkWgsl = {
  /** shaders/zfp/decode_blocks.wgsl, unchanged, over the pool. */
  decodeBlocks: [...pooledDecoder, zfpDecodeCore.decodeBlocks],
  blockRanges: [...pooledDecoder, part('chunk_ranges', chunkRanges)],
  neighbourhood: [gridSnippet, part('chunk_params', chunkParams), part('chunk_neighbourhood', chunkNeighbourhood)],
} satisfies Record<string, WgslPart[]>;
