// The zfp WGSL snippets (shaders/zfp/), composed per kernel.
import { gridSnippet } from '../gpu/dispatch.ts';
import type { WgslPart } from '../gpu/wgsl.ts';
import u64 from '../../shaders/zfp/u64.wgsl?raw';
import stream from '../../shaders/zfp/stream.wgsl?raw';
import streamAddress from '../../shaders/zfp/stream_address.wgsl?raw';
import poolAddress from '../../shaders/zfp/pool_address.wgsl?raw';
import codec from '../../shaders/zfp/codec.wgsl?raw';
import f64 from '../../shaders/zfp/f64.wgsl?raw';
import decodeBlock from '../../shaders/zfp/decode_block.wgsl?raw';
import decodeBlocks from '../../shaders/zfp/decode_blocks.wgsl?raw';
import decodeBlocksTiled from '../../shaders/zfp/decode_blocks_tiled.wgsl?raw';
import decodeVolume from '../../shaders/zfp/decode_volume.wgsl?raw';
import decodeVolumeTiled from '../../shaders/zfp/decode_volume_tiled.wgsl?raw';
import blockRanges from '../../shaders/zfp/block_ranges.wgsl?raw';
import poolRanges from '../../shaders/zfp/pool_ranges.wgsl?raw';
import encode from '../../shaders/zfp/encode.wgsl?raw';
import sourceValues from '../../shaders/zfp/source_values.wgsl?raw';
import streamError from '../../shaders/zfp/stream_error.wgsl?raw';

const part = (name: string, code: string): WgslPart => ({ name: `shaders/zfp/${name}.wgsl`, code });

// The decoder over a whole stream, or over chunks in a pool (page table).
const decoderBase = [
  gridSnippet,
  part('u64', u64),
  part('stream', stream),
  part('stream_address', streamAddress),
  part('codec', codec),
  part('decode_block', decodeBlock),
];
const poolDecoderBase = [
  gridSnippet,
  part('u64', u64),
  part('stream', stream),
  part('pool_address', poolAddress),
  part('codec', codec),
  part('decode_block', decodeBlock),
];

export const zfpWgsl = {
  decodeBlocks: [...decoderBase, part('decode_blocks', decodeBlocks)],
  decodePoolBlocks: [...poolDecoderBase, part('decode_blocks', decodeBlocks)],
  // GPU path (coalesced slot writes); needs the host's `const WG` in front (ZfpDecoder.create).
  decodeBlocksTiled: [...decoderBase, part('decode_blocks_tiled', decodeBlocksTiled)],
  decodePoolBlocksTiled: [...poolDecoderBase, part('decode_blocks_tiled', decodeBlocksTiled)],
  poolRanges: [...poolDecoderBase, part('block_ranges', blockRanges), part('pool_ranges', poolRanges)],
  decodeVolume: [...decoderBase, part('decode_volume', decodeVolume)],
  // GPU path of decodeVolume (tiles of 32 blocks along x, coalesced voxel stores)
  decodeVolumeTiled: [...decoderBase, part('decode_volume_tiled', decodeVolumeTiled)],
  blockRanges: [...decoderBase, part('block_ranges', blockRanges)],
  encode: [
    gridSnippet,
    part('u64', u64),
    part('codec', codec),
    part('f64', f64),
    part('source_values', sourceValues),
    part('encode', encode),
  ],
  // decoded minus source, per block (rate choice and the reported error)
  streamError: [...decoderBase, part('f64', f64), part('source_values', sourceValues), part('stream_error', streamError)],
} satisfies Record<string, WgslPart[]>;
