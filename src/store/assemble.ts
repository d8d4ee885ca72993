// A whole level of a store as one zfp fixed-rate stream, from all of its
// chunks: each chunk's 4^3 blocks are exactly the whole volume's blocks
// (converter/README.md, "Edge chunks"), so assembling is a reordering of
// bit runs (chunk-major -> volume raster order), never a decode. This is
// the in-core reference for a level (benchmarks, tests) and the CLI's path
// for a fully fetched level until the GPU chunk pool (ChunkedVolume) takes
// over; it needs every chunk of the level.
import { bitsPerBlockForRate, blockGridOf, fixedRateStreamBytes } from '../zfp/format.ts';
import { readBits, writeBits, writeZfpHeader } from '../zfp/header.ts';
import type { ChunkIndex, ChunkLevelLayout } from './types.ts';

function copyBits(src: Uint8Array, srcBit: number, dst: Uint8Array, dstBit: number, count: number): void {
  if (srcBit % 8 === 0 && dstBit % 8 === 0 && count % 8 === 0) {
    dst.set(src.subarray(srcBit / 8, (srcBit + count) / 8), dstBit / 8);
    return;
  }
  for (let done = 0; done < count; done += 32) {
    const n = Math.min(32, count - done);
    writeBits(dst, dstBit + done, n, readBits(src, srcBit + done, n));
  }
}

/** The level's stream (header + blocks in raster order), from every chunk's stored bytes. */
/** Why a level cannot be one zfp stream (a zfp header holds 65536 voxels per axis; one GPU buffer), or null. */
export function assemblyLimit(layout: ChunkLevelLayout, maxBytes: number): string | null {
  if (layout.dims.some((n) => n > 0x10000))
    return `${layout.name} is ${layout.dims.join('x')}: one zfp stream holds at most 65536 voxels per axis`;
  const [bx, by, bz] = blockGridOf(layout.dims);
  const bytes = fixedRateStreamBytes(bx * by * bz, bitsPerBlockForRate(layout.rate), 96);
  if (bytes > maxBytes) return `${layout.name} as one stream is ${bytes} bytes, above ${maxBytes}`;
  return null;
}

export function assembleLevelStream(layout: ChunkLevelLayout, chunkBytes: (chunk: ChunkIndex) => Uint8Array): Uint8Array {
  const bits = bitsPerBlockForRate(layout.rate);
  const header = writeZfpHeader(layout.dims, bits);
  const [bx, by, bz] = blockGridOf(layout.dims);
  const out = new Uint8Array(fixedRateStreamBytes(bx * by * bz, bits, header.bits));
  out.set(header.bytes);
  const per = layout.chunkEdge / 4;
  const [gx, gy, gz] = layout.chunkGrid;
  const srcHeaderBits = header.bits; // chunks carry the same kind of header (same rate)
  for (let cz = 0; cz < gz; cz++) {
    for (let cy = 0; cy < gy; cy++) {
      for (let cx = 0; cx < gx; cx++) {
        const src = chunkBytes(cx + gx * (cy + gy * cz));
        for (let k = 0; k < per && cz * per + k < bz; k++) {
          for (let j = 0; j < per && cy * per + j < by; j++) {
            // a run of blocks along x is contiguous in both streams
            const run = Math.min(per, bx - cx * per);
            const srcBlock = per * (j + per * k);
            const dstBlock = cx * per + bx * (cy * per + j + by * (cz * per + k));
            copyBits(src, srcHeaderBits + srcBlock * bits, out, header.bits + dstBlock * bits, run * bits);
          }
        }
      }
    }
  }
  return out;
}
