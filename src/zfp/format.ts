// What a zfp file holds, decided before anything touches the GPU: the field
// (3D float32 only), the fixed rate, the block grid and where each block's
// bits are. Accepts zfp's own files (96- or 148-bit header) and the original
// project's header-less fixed-rate streams whose name carries shape and rate
// (`name_XxYxZ_float32.raw.crate4.zfp`, or `..._float32.zfp` plus a rate).
// Everything else is rejected with a ZfpFormatError naming the file and why.
//
// Fixed-rate layout (zfp 1.0.1): blocks of 4x4x4 values in raster block order
// (x fastest), each exactly `bitsPerBlock` bits, block b at stream bit
// `payloadBitOffset + b * bitsPerBlock`; bits are LSB-first in little-endian
// 64-bit words; zfp pads the stream with zeros to a whole 64-bit word.

import { DTYPES, type DType } from '../core/dtype.ts';
import { formatDims, parseVolumeName, type Dims } from '../core/naming.ts';
import { describeMode, hasZfpMagic, parseZfpHeader, ZfpFormatError, type ZfpHeader } from './header.ts';

export { ZfpFormatError } from './header.ts';

/** Values per 3D block. */
export const BLOCK_VALUES = 64;
/** 1 "non-zero" bit + 8 exponent bits: the least a float32 block can take. */
export const MIN_FLOAT_BLOCK_BITS = 9;
/** Block ids are u32 on the GPU. */
export const MAX_BLOCKS = 0xffffffff;

export interface ZfpStreamInfo {
  fileName: string;
  /** Field size nx, ny, nz (x fastest). */
  dims: Dims;
  scalarType: 'float32';
  /** The stream starts with zfp's header. */
  hasHeader: boolean;
  /** 0 (header-less), 96 or 148: where block 0 starts. */
  payloadBitOffset: number;
  bitsPerBlock: number;
  /** bitsPerBlock / 64. */
  rate: number;
  /** Blocks per axis: ceil(n / 4). */
  blockGrid: Dims;
  blockCount: number;
  /** payloadBitOffset + blockCount * bitsPerBlock (exact: < 2^53). */
  endBit: number;
  /** Bytes the blocks need: ceil(endBit / 8). */
  requiredBytes: number;
  /** What zfp writes: endBit rounded up to a 64-bit word, in bytes. */
  paddedBytes: number;
  fileBytes: number;
  /** Human-readable mode, e.g. "fixed rate 4 bits/value (256 bits per block)". */
  mode: string;
  /** Oddities that do not prevent decoding (e.g. bytes after the stream). */
  notes: string[];
}

/**
 * Bits per 3D block for a rate, as zfp 1.0.1's zfp_stream_set_rate(..., align=0)
 * computes them: floor(64 * rate + 0.5). (zfp 1.0.1 does not raise this to the
 * 9 bits a float block needs; such streams are rejected here.)
 */
export function bitsPerBlockForRate(rate: number): number {
  if (!Number.isFinite(rate) || rate <= 0) throw new RangeError(`rate must be a positive number (got ${rate})`);
  return Math.floor(BLOCK_VALUES * rate + 0.5);
}

export function blockGridOf(dims: Dims): Dims {
  return [Math.ceil(dims[0] / 4), Math.ceil(dims[1] / 4), Math.ceil(dims[2] / 4)];
}

/** Bytes of a fixed-rate stream as zfp writes it (padded to a 64-bit word). */
export function fixedRateStreamBytes(blockCount: number, bitsPerBlock: number, payloadBitOffset = 0): number {
  return Math.ceil((payloadBitOffset + blockCount * bitsPerBlock) / 64) * 8;
}

export interface OpenZfpOptions {
  /** Rate of a header-less stream (overrides a rate in the name). */
  rate?: number;
}

function fail(fileName: string, message: string): never {
  throw new ZfpFormatError(`${fileName}: ${message}`);
}

const RECOMPRESS =
  'Re-compress it with a fixed rate: `zfp -f -3 X Y Z -r R -h`, zfpy.compress_numpy(a.astype(np.float32), rate=R), or `npm run cli -- compress`.';

function checkBitsPerBlock(fileName: string, bits: number, rateText: string): void {
  if (bits < MIN_FLOAT_BLOCK_BITS) {
    fail(
      fileName,
      `${rateText} gives ${bits} bits per block, fewer than the ${MIN_FLOAT_BLOCK_BITS} a float32 block needs (1 + 8 exponent bits); zfp writes such streams with blocks of varying length, which cannot be decoded block by block (use a rate of at least 0.1328125)`,
    );
  }
  if (bits > 0x8000) fail(fileName, `${rateText} gives ${bits} bits per block; zfp allows at most 32768`);
}

export function checkRate(fileName: string, rate: number, where: string): void {
  if (!Number.isFinite(rate) || rate <= 0) fail(fileName, `the rate ${where} (${rate}) is not a positive number of bits per value`);
}

function checkDims(fileName: string, dims: Dims, where: string): void {
  if (dims.some((n) => !Number.isSafeInteger(n) || n < 1))
    fail(fileName, `absurd size ${formatDims(dims)} ${where}: every dimension must be at least 1`);
  const grid = blockGridOf(dims);
  const blocks = grid[0] * grid[1] * grid[2];
  if (blocks > MAX_BLOCKS) {
    fail(
      fileName,
      `absurd size ${formatDims(dims)} ${where}: ${blocks.toExponential(3)} blocks of 4x4x4, more than the ${MAX_BLOCKS} (2^32 - 1) a stream may have`,
    );
  }
}

function finish(
  fileName: string,
  fileBytes: number,
  dims: Dims,
  bitsPerBlock: number,
  payloadBitOffset: number,
  mode: string,
): ZfpStreamInfo {
  const blockGrid = blockGridOf(dims);
  const blockCount = blockGrid[0] * blockGrid[1] * blockGrid[2];
  const endBit = payloadBitOffset + blockCount * bitsPerBlock;
  if (!Number.isSafeInteger(endBit)) fail(fileName, `absurd size ${formatDims(dims)}: the stream would be ${endBit / 8} bytes`);
  return {
    fileName,
    dims,
    scalarType: 'float32',
    hasHeader: payloadBitOffset > 0,
    payloadBitOffset,
    bitsPerBlock,
    rate: bitsPerBlock / BLOCK_VALUES,
    blockGrid,
    blockCount,
    endBit,
    requiredBytes: Math.ceil(endBit / 8),
    paddedBytes: Math.ceil(endBit / 64) * 8,
    fileBytes,
    mode,
    notes: [],
  };
}

function fromHeader(fileName: string, fileBytes: number, header: ZfpHeader): ZfpStreamInfo {
  const { size, dimensionality: d, mode } = header;
  const shape = size.slice(0, d).join('x');
  if (d !== 3) fail(fileName, `the zfp header describes a ${d}D field (${shape}); only 3D volumes are supported`);
  if (header.scalarType !== 'float32') {
    fail(fileName, `the zfp stream holds ${header.scalarType} values; only float32 streams are supported (compress a float32 array)`);
  }
  const modeText = describeMode(mode, 3);
  if (mode.kind !== 'fixed-rate') {
    fail(
      fileName,
      `the zfp stream is ${modeText}, not fixed-rate. Only fixed-rate streams have blocks of one size that can be decoded independently. ${RECOMPRESS}`,
    );
  }
  const dims: Dims = [size[0], size[1], size[2]];
  checkDims(fileName, dims, 'in the zfp header');
  checkBitsPerBlock(fileName, mode.maxBits, `the header's fixed rate ${mode.maxBits / 64}`);
  const info = finish(fileName, fileBytes, dims, mode.maxBits, header.headerBits, modeText);
  if (fileBytes < info.requiredBytes) {
    fail(
      fileName,
      `truncated: the header promises ${formatDims(dims)} float32 at ${info.bitsPerBlock} bits per block (${info.blockCount} blocks), ` +
        `${info.requiredBytes} bytes with the header, but the file has ${fileBytes} bytes`,
    );
  }
  if (fileBytes > info.paddedBytes) info.notes.push(`${fileBytes - info.paddedBytes} bytes follow the stream and are ignored`);
  return info;
}

function headerless(fileName: string, fileBytes: number, opts: OpenZfpOptions): ZfpStreamInfo {
  const name = parseVolumeName(fileName);
  if (!name.dims) {
    fail(
      fileName,
      'no zfp header (the file does not start with "zfp") and the name carries no shape; ' +
        'a header-less stream must be named like name_XxYxZ_float32.raw.crate4.zfp (or give its rate with --rate)',
    );
  }
  if (name.dtype && name.dtype !== 'float32') fail(fileName, `the name says ${name.dtype}; only float32 zfp streams are supported`);
  const rate = opts.rate ?? name.rate;
  if (rate === undefined) {
    checkDims(fileName, name.dims, 'in the file name');
    const grid = blockGridOf(name.dims);
    const blocks = grid[0] * grid[1] * grid[2];
    // rates whose stream has exactly this size
    const lo = Math.max(MIN_FLOAT_BLOCK_BITS, Math.floor(((fileBytes - 8) * 8) / blocks));
    const fits: number[] = [];
    for (let bits = lo; bits <= Math.ceil((fileBytes * 8) / blocks) && bits <= 0x8000; bits++) {
      if (fixedRateStreamBytes(blocks, bits) === fileBytes) fits.push(bits / BLOCK_VALUES);
    }
    const hint =
      fits.length === 0
        ? `; no fixed rate gives ${fileBytes} bytes for ${formatDims(name.dims)}, so this is not a fixed-rate stream (fixed-precision and fixed-accuracy streams have no fixed size)`
        : ` (the size fits rate ${fits.join(' or ')})`;
    fail(
      fileName,
      `no zfp header and no rate: give the rate (--rate R) or name the file ${name.base}_${formatDims(name.dims)}_float32.raw.crateR.zfp${hint}`,
    );
  }
  checkRate(fileName, rate, opts.rate === undefined ? 'in the file name' : 'given');
  const bits = bitsPerBlockForRate(rate);
  checkDims(fileName, name.dims, 'in the file name');
  checkBitsPerBlock(fileName, bits, `rate ${rate}`);
  const info = finish(fileName, fileBytes, name.dims, bits, 0, `fixed rate ${bits / 64} bits/value (${bits} bits per block), no header`);
  if (fileBytes !== info.paddedBytes) {
    const what = fileBytes < info.paddedBytes ? 'truncated, or not' : 'not';
    fail(
      fileName,
      `a header-less fixed-rate ${rate} stream of ${formatDims(name.dims)} float32 is ${info.paddedBytes} bytes (${info.blockCount} blocks of ${bits} bits), ` +
        `but the file has ${fileBytes}: ${what} a fixed-rate stream of that shape and rate (fixed-precision and fixed-accuracy streams have no fixed size)`,
    );
  }
  return info;
}

/**
 * Describes a zfp file from its first bytes (>= 20 when the file has them)
 * and its size, without reading the rest. Throws ZfpFormatError.
 */
export function describeZfpStream(fileName: string, fileBytes: number, head: Uint8Array, opts: OpenZfpOptions = {}): ZfpStreamInfo {
  if (hasZfpMagic(head)) {
    let header: ZfpHeader;
    try {
      header = parseZfpHeader(head);
    } catch (e) {
      if (e instanceof ZfpFormatError) fail(fileName, e.message);
      throw e;
    }
    return fromHeader(fileName, fileBytes, header);
  }
  return headerless(fileName, fileBytes, opts);
}

/** Describes the whole file `bytes` (see describeZfpStream). */
export function openZfpStream(bytes: Uint8Array, fileName: string, opts: OpenZfpOptions = {}): ZfpStreamInfo {
  return describeZfpStream(fileName, bytes.byteLength, bytes.subarray(0, 64), opts);
}

/** Stream info for a volume we are about to compress. */
export function planZfpStream(fileName: string, dims: Dims, rate: number, withHeader: boolean): ZfpStreamInfo {
  checkRate(fileName, rate, 'asked for');
  const bits = bitsPerBlockForRate(rate);
  checkDims(fileName, dims, '');
  checkBitsPerBlock(fileName, bits, `rate ${rate}`);
  if (withHeader && dims.some((n) => n > 0x10000))
    fail(fileName, `a zfp header holds sizes up to 65536 per axis, not ${formatDims(dims)}; write it without header`);
  const payload = withHeader ? (bits > 2048 ? 148 : 96) : 0;
  const info = finish(fileName, 0, dims, bits, payload, `fixed rate ${bits / 64} bits/value (${bits} bits per block)`);
  info.fileBytes = info.paddedBytes;
  return info;
}

/** The input types the encoder accepts (converted to float32 like numpy's astype). */
export const ENCODER_DTYPES: readonly DType[] = DTYPES;
