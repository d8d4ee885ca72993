// The zfp stream header (zfp 1.0, codec version 5): 32 bits of magic and
// version, 52 bits of field metadata, then the compression mode: 12 bits, or
// 64 bits when those 12 bits are 0xfff (the 64-bit word's low 12 bits ARE the
// short field: the long mode occupies bits 84..147, so such a header is 148
// bits). Bits are read LSB-first from 64-bit little-endian words, i.e. stream
// bit n is bit n % 8 of byte n / 8.
// Layout: ../shared/data/README.md ("ZFP stream format"); mode encoding as in
// zfp's zfp_stream_mode / zfp_stream_set_mode / zfp_stream_compression_mode.

export const ZFP_MAGIC = [0x7a, 0x66, 0x70] as const; // 'z' 'f' 'p'
export const ZFP_CODEC_VERSION = 5;
export const ZFP_SHORT_HEADER_BITS = 96;
/** 32 magic + 52 meta + 64 mode bits. */
export const ZFP_LONG_HEADER_BITS = 148;
/** Largest 12-bit mode value; 4095 announces the 64-bit mode word. */
export const ZFP_MODE_SHORT_MAX = 4094;
/** zfp's limits on the per-block parameters (zfp.h). */
export const ZFP_MIN_BITS = 1;
export const ZFP_MAX_BITS = 16658;
export const ZFP_MAX_PREC = 64;
export const ZFP_MIN_EXP = -1074;

export type ZfpScalarType = 'int32' | 'int64' | 'float32' | 'float64';
const SCALAR_TYPES: ZfpScalarType[] = ['int32', 'int64', 'float32', 'float64'];

export type ZfpModeKind = 'fixed-rate' | 'fixed-precision' | 'fixed-accuracy' | 'reversible' | 'expert';

export interface ZfpMode {
  kind: ZfpModeKind;
  /** Bits per block in fixed-rate mode (minbits = maxbits). */
  maxBits: number;
  minBits: number;
  maxPrec: number;
  minExp: number;
  /** The mode as stored: 12-bit value, or the 64-bit word (as bigint) for long modes. */
  raw: number | bigint;
}

export interface ZfpHeader {
  codecVersion: number;
  scalarType: ZfpScalarType;
  dimensionality: 1 | 2 | 3 | 4;
  /** nx, ny, nz, nw (unused dimensions are 0). */
  size: [number, number, number, number];
  mode: ZfpMode;
  /** Where the compressed blocks start: 96 (12-bit mode) or 148 (64-bit mode). */
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
    if (byte === undefined) throw new ZfpFormatError(`the file ends at bit ${bit}, inside the zfp header`);
    if ((byte >> (bit % 8)) & 1) value |= 1n << BigInt(i);
  }
  return value;
}

/** Writes the low `count` bits of `value` at `bitOffset` (ORed into zeroed bytes). */
export function writeBits(bytes: Uint8Array, bitOffset: number, count: number, value: bigint): void {
  for (let i = 0; i < count; i++) {
    if ((value >> BigInt(i)) & 1n) {
      const bit = bitOffset + i;
      bytes[bit >> 3] |= 1 << (bit & 7);
    }
  }
}

export function hasZfpMagic(bytes: Uint8Array): boolean {
  return bytes.length >= 3 && bytes[0] === ZFP_MAGIC[0] && bytes[1] === ZFP_MAGIC[1] && bytes[2] === ZFP_MAGIC[2];
}

/** zfp's classification of (minbits, maxbits, maxprec, minexp). */
function classify(minBits: number, maxBits: number, maxPrec: number, minExp: number): ZfpModeKind {
  if (minBits === ZFP_MIN_BITS && maxBits === ZFP_MAX_BITS && maxPrec === ZFP_MAX_PREC && minExp === ZFP_MIN_EXP) return 'expert';
  if (minBits === maxBits && maxBits >= 1 && maxBits <= ZFP_MAX_BITS && maxPrec >= ZFP_MAX_PREC && minExp === ZFP_MIN_EXP)
    return 'fixed-rate';
  if (minBits <= ZFP_MIN_BITS && maxBits >= ZFP_MAX_BITS && maxPrec >= 1 && minExp === ZFP_MIN_EXP) return 'fixed-precision';
  if (minBits <= ZFP_MIN_BITS && maxBits >= ZFP_MAX_BITS && maxPrec >= ZFP_MAX_PREC && minExp >= ZFP_MIN_EXP) return 'fixed-accuracy';
  if (minBits <= ZFP_MIN_BITS && maxBits >= ZFP_MAX_BITS && maxPrec >= ZFP_MAX_PREC && minExp < ZFP_MIN_EXP) return 'reversible';
  return 'expert';
}

/** Decodes a mode: the 12-bit value (< 4095) or the 64-bit word. */
export function decodeZfpMode(mode: bigint): ZfpMode {
  if (mode <= BigInt(ZFP_MODE_SHORT_MAX)) {
    const short = Number(mode);
    if (short < 2048)
      return { kind: 'fixed-rate', minBits: short + 1, maxBits: short + 1, maxPrec: ZFP_MAX_PREC, minExp: ZFP_MIN_EXP, raw: short };
    if (short < 2048 + 128) {
      return {
        kind: 'fixed-precision',
        minBits: ZFP_MIN_BITS,
        maxBits: ZFP_MAX_BITS,
        maxPrec: short + 1 - 2048,
        minExp: ZFP_MIN_EXP,
        raw: short,
      };
    }
    if (short === 2048 + 128)
      return {
        kind: 'reversible',
        minBits: ZFP_MIN_BITS,
        maxBits: ZFP_MAX_BITS,
        maxPrec: ZFP_MAX_PREC,
        minExp: ZFP_MIN_EXP - 1,
        raw: short,
      };
    return {
      kind: 'fixed-accuracy',
      minBits: ZFP_MIN_BITS,
      maxBits: ZFP_MAX_BITS,
      maxPrec: ZFP_MAX_PREC,
      minExp: short + ZFP_MIN_EXP - (2048 + 128) - 1,
      raw: short,
    };
  }
  // 64-bit word: 12 bits 0xfff, minbits-1 (15), maxbits-1 (15), maxprec-1 (7), minexp+16495 (15).
  let w = mode >> 12n;
  const minBits = Number(w & 0x7fffn) + 1;
  w >>= 15n;
  const maxBits = Number(w & 0x7fffn) + 1;
  w >>= 15n;
  const maxPrec = Number(w & 0x7fn) + 1;
  w >>= 7n;
  const minExp = Number(w & 0x7fffn) - 16495;
  return { kind: classify(minBits, maxBits, maxPrec, minExp), minBits, maxBits, maxPrec, minExp, raw: mode };
}

/** The mode word zfp writes for fixed rate with `bitsPerBlock` (zfp_stream_mode). */
export function fixedRateModeWord(bitsPerBlock: number): bigint {
  if (!Number.isInteger(bitsPerBlock) || bitsPerBlock < 1 || bitsPerBlock > 0x8000)
    throw new RangeError(`bits per block ${bitsPerBlock} out of range`);
  if (bitsPerBlock <= 2048) return BigInt(bitsPerBlock - 1);
  const minexp = BigInt(ZFP_MIN_EXP + 16495);
  const maxprec = BigInt(ZFP_MAX_PREC - 1);
  const bits = BigInt(bitsPerBlock - 1);
  return (((((((minexp << 7n) | maxprec) << 15n) | bits) << 15n) | bits) << 12n) | 0xfffn;
}

/** Parses the header at the start of `bytes`; throws ZfpFormatError. */
export function parseZfpHeader(bytes: Uint8Array): ZfpHeader {
  if (bytes.length < ZFP_SHORT_HEADER_BITS / 8)
    throw new ZfpFormatError(`the file is ${bytes.length} bytes, shorter than a zfp header (12 bytes)`);
  if (!hasZfpMagic(bytes)) throw new ZfpFormatError('wrong magic: a zfp header starts with the bytes "zfp" (7a 66 70)');
  const codecVersion = bytes[3];
  if (codecVersion !== ZFP_CODEC_VERSION) {
    throw new ZfpFormatError(
      `zfp codec version ${codecVersion} is not supported (expected ${ZFP_CODEC_VERSION}, as written by zfp 0.5.5 to 1.0.x)`,
    );
  }
  const meta = readBits(bytes, 32, 52);
  const typeCode = Number(meta & 3n);
  const dimensionality = (Number((meta >> 2n) & 3n) + 1) as 1 | 2 | 3 | 4;
  const sizeBits = meta >> 4n;
  const size: [number, number, number, number] = [0, 0, 0, 0];
  const perDim = [48, 24, 16, 12][dimensionality - 1];
  const mask = (1n << BigInt(perDim)) - 1n;
  for (let d = 0; d < dimensionality; d++) size[d] = Number((sizeBits >> BigInt(d * perDim)) & mask) + 1;
  const short = readBits(bytes, 84, 12);
  const long = short > BigInt(ZFP_MODE_SHORT_MAX);
  const modeWord = long ? readBits(bytes, 84, 64) : short;
  return {
    codecVersion,
    scalarType: SCALAR_TYPES[typeCode],
    dimensionality,
    size,
    mode: decodeZfpMode(modeWord),
    headerBits: long ? ZFP_LONG_HEADER_BITS : ZFP_SHORT_HEADER_BITS,
  };
}

/**
 * The header zfp writes for a 3D float32 field in fixed-rate mode (as
 * `zfpy.compress_numpy(a, rate=R, write_header=True)`): 96 bits, or 148 when
 * bitsPerBlock > 2048. Returned in ceil(bits/8) bytes; the last byte of a
 * 148-bit header also holds the first 4 payload bits (zero here).
 */
export function writeZfpHeader(dims: readonly [number, number, number], bitsPerBlock: number): { bytes: Uint8Array; bits: number } {
  for (const n of dims) {
    if (!Number.isInteger(n) || n < 1 || n > 0x10000)
      throw new ZfpFormatError(`a zfp header holds 3D sizes from 1 to 65536, not ${dims.join('x')}`);
  }
  const mode = fixedRateModeWord(bitsPerBlock);
  const long = mode > BigInt(ZFP_MODE_SHORT_MAX);
  const bits = long ? ZFP_LONG_HEADER_BITS : ZFP_SHORT_HEADER_BITS;
  const bytes = new Uint8Array(Math.ceil(bits / 8));
  bytes.set([ZFP_MAGIC[0], ZFP_MAGIC[1], ZFP_MAGIC[2], ZFP_CODEC_VERSION]);
  const [nx, ny, nz] = dims.map((n) => BigInt(n - 1));
  const meta = (((nz << 32n) | (ny << 16n) | nx) << 4n) | (2n << 2n) | 2n; // 3D (2), float (type 3 - 1)
  writeBits(bytes, 32, 52, meta);
  writeBits(bytes, 84, long ? 64 : 12, mode);
  return { bytes, bits };
}

export function describeMode(mode: ZfpMode, dimensionality: number): string {
  const values = 4 ** dimensionality;
  switch (mode.kind) {
    case 'fixed-rate':
      return `fixed rate ${mode.maxBits / values} bits/value (${mode.maxBits} bits per block)`;
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
