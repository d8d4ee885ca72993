// The zfp stream header (zfp 1.0, codec version 5): 32 bits of magic and
// version, 52 bits of field metadata, a 12-bit mode (and a 64-bit expert mode
// word when the short mode is 4095). Bits are read LSB-first from 64-bit
// little-endian words, i.e. stream bit n is bit n % 8 of byte n / 8.
// Layout: ../shared/data/README.md ("ZFP stream format").

export const ZFP_MAGIC = [0x7a, 0x66, 0x70] as const; // 'z' 'f' 'p'
export const ZFP_CODEC_VERSION = 5;
export const ZFP_SHORT_HEADER_BITS = 96;
export const ZFP_LONG_HEADER_BITS = 160;

export type ZfpScalarType = 'int32' | 'int64' | 'float32' | 'float64';
const SCALAR_TYPES: ZfpScalarType[] = ['int32', 'int64', 'float32', 'float64'];

export type ZfpModeKind = 'fixed-rate' | 'fixed-precision' | 'fixed-accuracy' | 'reversible' | 'expert';

export interface ZfpMode {
  kind: ZfpModeKind;
  /** Bits per block in fixed-rate mode (minbits = maxbits). */
  maxBits?: number;
  minBits?: number;
  maxPrec?: number;
  minExp?: number;
}

export interface ZfpHeader {
  codecVersion: number;
  scalarType: ZfpScalarType;
  dimensionality: 1 | 2 | 3 | 4;
  /** nx, ny, nz, nw (unused dimensions are 0). */
  size: [number, number, number, number];
  mode: ZfpMode;
  /** Where the compressed blocks start. */
  headerBits: number;
}

export class ZfpFormatError extends Error {
  constructor(message: string) {
    super(message);
    this.name = 'ZfpFormatError';
  }
}

/** Reads `count` (<= 64) bits at `bitOffset` of an LSB-first bit stream. */
export function readBits(bytes: Uint8Array, bitOffset: number, count: number): bigint {
  let value = 0n;
  for (let i = 0; i < count; i++) {
    const bit = bitOffset + i;
    const byte = bytes[Math.floor(bit / 8)];
    if (byte === undefined) throw new ZfpFormatError(`stream ends at bit ${bit} while reading the header`);
    if ((byte >> (bit % 8)) & 1) value |= 1n << BigInt(i);
  }
  return value;
}

export function hasZfpMagic(bytes: Uint8Array): boolean {
  return bytes.length >= 4 && bytes[0] === ZFP_MAGIC[0] && bytes[1] === ZFP_MAGIC[1] && bytes[2] === ZFP_MAGIC[2];
}

function decodeMode(short: number, expert: bigint | undefined): ZfpMode {
  if (short < 2048) return { kind: 'fixed-rate', maxBits: short + 1, minBits: short + 1 };
  if (short < 2176) return { kind: 'fixed-precision', maxPrec: short - 2048 + 1 };
  if (short === 2176) return { kind: 'reversible' };
  if (short < 4095) return { kind: 'fixed-accuracy', minExp: short - 2177 - 1074 };
  if (expert === undefined) throw new ZfpFormatError('expert mode word missing');
  // 64-bit expert word: 12 bits 0xfff, then minbits-1 (15), maxbits-1 (15),
  // maxprec-1 (7), minexp+16495 (15).
  let w = expert >> 12n;
  const minBits = Number(w & 0x7fffn) + 1;
  w >>= 15n;
  const maxBits = Number(w & 0x7fffn) + 1;
  w >>= 15n;
  const maxPrec = Number(w & 0x7fn) + 1;
  w >>= 7n;
  const minExp = Number(w & 0x7fffn) - 16495;
  const kind: ZfpModeKind = minBits === maxBits ? 'fixed-rate' : 'expert';
  return { kind, minBits, maxBits, maxPrec, minExp };
}

/** Parses the header at the start of `bytes`; throws ZfpFormatError. */
export function parseZfpHeader(bytes: Uint8Array): ZfpHeader {
  if (bytes.length < ZFP_SHORT_HEADER_BITS / 8) throw new ZfpFormatError(`file is ${bytes.length} bytes, shorter than a zfp header (12 bytes)`);
  if (!hasZfpMagic(bytes)) throw new ZfpFormatError('no zfp header (the file does not start with the magic "zfp")');
  const codecVersion = bytes[3];
  if (codecVersion !== ZFP_CODEC_VERSION) {
    throw new ZfpFormatError(`zfp codec version ${codecVersion} is not supported (expected ${ZFP_CODEC_VERSION}, as written by zfp 0.5.5 to 1.0.x)`);
  }
  const meta = readBits(bytes, 32, 52);
  const typeCode = Number(meta & 3n);
  const dimensionality = (Number((meta >> 2n) & 3n) + 1) as 1 | 2 | 3 | 4;
  const sizeBits = meta >> 4n;
  const size: [number, number, number, number] = [0, 0, 0, 0];
  const perDim = [48, 24, 16, 12][dimensionality - 1];
  const mask = (1n << BigInt(perDim)) - 1n;
  for (let d = 0; d < dimensionality; d++) size[d] = Number((sizeBits >> BigInt(d * perDim)) & mask) + 1;
  const short = Number(readBits(bytes, 84, 12));
  const expert = short === 4095 ? readBits(bytes, 96, 64) : undefined;
  return {
    codecVersion,
    scalarType: SCALAR_TYPES[typeCode],
    dimensionality,
    size,
    mode: decodeMode(short, expert),
    headerBits: short === 4095 ? ZFP_LONG_HEADER_BITS : ZFP_SHORT_HEADER_BITS,
  };
}

export function describeMode(mode: ZfpMode, dimensionality: number): string {
  const values = 4 ** dimensionality;
  switch (mode.kind) {
    case 'fixed-rate':
      return `fixed rate ${(mode.maxBits ?? 0) / values} bits/value (${mode.maxBits} bits per block)`;
    case 'fixed-precision':
      return `fixed precision ${mode.maxPrec}`;
    case 'fixed-accuracy':
      return `fixed accuracy (tolerance 2^${mode.minExp})`;
    case 'reversible':
      return 'reversible (lossless)';
    case 'expert':
      return `expert mode (minbits ${mode.minBits}, maxbits ${mode.maxBits}, maxprec ${mode.maxPrec}, minexp ${mode.minExp})`;
  }
}
