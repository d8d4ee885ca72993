// The zfp WGSL snippets (shaders/zfp/), composed per kernel.
import { gridSnippet } from '../gpu/dispatch.ts';
import type { WgslPart } from '../gpu/wgsl.ts';
import u64 from '../../shaders/zfp/u64.wgsl?raw';
import stream from '../../shaders/zfp/stream.wgsl?raw';
import streamBlocks from '../../shaders/zfp/stream_blocks.wgsl?raw';
import codec from '../../shaders/zfp/codec.wgsl?raw';
import f64 from '../../shaders/zfp/f64.wgsl?raw';
import decodeBlock from '../../shaders/zfp/decode_block.wgsl?raw';
import decodeBlocks from '../../shaders/zfp/decode_blocks.wgsl?raw';
import decodeVolume from '../../shaders/zfp/decode_volume.wgsl?raw';
import blockRanges from '../../shaders/zfp/block_ranges.wgsl?raw';
import encode from '../../shaders/zfp/encode.wgsl?raw';

const part = (name: string, code: string): WgslPart => ({ name: `shaders/zfp/${name}.wgsl`, code });

/**
 * The decode core without block addressing: the stream's reader, the codec
 * and decode_block, which calls `block_start(b)`. A contiguous stream composes
 * stream_blocks.wgsl; a pool of chunks composes its own (src/store).
 */
export const zfpDecodeCore = { u64: part('u64', u64), stream: part('stream', stream), codec: part('codec', codec), decodeBlock: part('decode_block', decodeBlock), decodeBlocks: part('decode_blocks', decodeBlocks) };

const decoderBase = [gridSnippet, zfpDecodeCore.u64, zfpDecodeCore.stream, part('stream_blocks', streamBlocks), zfpDecodeCore.codec, zfpDecodeCore.decodeBlock];

export const zfpWgsl = {
  decodeBlocks: [...decoderBase, zfpDecodeCore.decodeBlocks],
  decodeVolume: [...decoderBase, part('decode_volume', decodeVolume)],
  blockRanges: [...decoderBase, part('block_ranges', blockRanges)],
  encode: [gridSnippet, part('u64', u64), part('codec', codec), part('f64', f64), part('encode', encode)],
} satisfies Record<string, WgslPart[]>;
