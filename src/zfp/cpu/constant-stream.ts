// A zfp fixed-rate stream (with header) of a volume where every value is the
// same: what a Zarr chunk absent from its store holds (the array's fill
// value). Encoded once on the CPU (every block is the same bits), so a
// missing chunk goes to the GPU pool like any other.
import { bitsPerBlockForRate, fixedRateStreamBytes } from '../format.ts';
import { writeZfpHeader } from '../header.ts';
import { BitWriter, encodeBlock } from './codec.ts';

/** The stream zfpy writes for a C^3 float32 chunk of `value` at `rate`, header included. */
export function constantChunkStream(edge: number, rate: number, value: number): Uint8Array {
  const bits = bitsPerBlockForRate(rate);
  const blocks = (edge / 4) ** 3;
  const header = writeZfpHeader([edge, edge, edge], bits);
  const out = new Uint8Array(fixedRateStreamBytes(blocks, bits, header.bits));
  out.set(header.bytes);
  const words = new Uint32Array(out.buffer, 0, out.byteLength >> 2);
  const block = new Float32Array(64).fill(value);
  const w = new BitWriter(words, header.bits);
  for (let b = 0; b < blocks; b++) encodeBlock(block, bits, w);
  return out;
}
