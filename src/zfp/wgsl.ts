// The zfp WGSL snippets (shaders/zfp/), composed per kernel.
import { gridSnippet } from '../gpu/dispatch.ts';
import type { WgslPart } from '../gpu/wgsl.ts';
import u64 from '../../shaders/zfp/u64.wgsl?raw';
import stream from '../../shaders/zfp/stream.wgsl?raw';
import codec from '../../shaders/zfp/codec.wgsl?raw';
import f64 from '../../shaders/zfp/f64.wgsl?raw';
import decodeBlock from '../../shaders/zfp/decode_block.wgsl?raw';
import decodeBlocks from '../../shaders/zfp/decode_blocks.wgsl?raw';
import decodeVolume from '../../shaders/zfp/decode_volume.wgsl?raw';
import blockRanges from '../../shaders/zfp/block_ranges.wgsl?raw';
import encode from '../../shaders/zfp/encode.wgsl?raw';

const part = (name: string, code: string): WgslPart => ({ name: `shaders/zfp/${name}.wgsl`, code });

const decoderBase = [gridSnippet, part('u64', u64), part('stream', stream), part('codec', codec), part('decode_block', decodeBlock)];

export const zfpWgsl = {
  decodeBlocks: [...decoderBase, part('decode_blocks', decodeBlocks)],
  decodeVolume: [...decoderBase, part('decode_volume', decodeVolume)],
  blockRanges: [...decoderBase, part('block_ranges', blockRanges)],
  encode: [gridSnippet, part('u64', u64), part('codec', codec), part('f64', f64), part('encode', encode)],
} satisfies Record<string, WgslPart[]>;
