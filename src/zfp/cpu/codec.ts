// CPU twin of the WGSL codec (shaders/zfp/): zfp 1.0.1's fixed-rate 3D
// float32 block coder, written from zfp's documented algorithm. Used by tests
// (to localise a GPU mismatch) and for small jobs; the GPU path is the product.
//
// Per block (encoder; the decoder runs it backwards):
//   1. common exponent emax = exponent of max |x| (frexp convention); e = emax + 127;
//      e = 0 (all zeros) is coded as a single 0 bit, else 1 bit + 8 bits of e;
//   2. block floating point: i = trunc(x * 2^(30 - emax)) as int32;
//   3. decorrelating lifting transform along x, then y, then z;
//   4. reorder by sequency (PERM) and map to negabinary (u = (i + NB) ^ NB);
//   5. embedded coding of bit planes 31..0 with group tests, cut at the budget.
// Partial blocks are padded per axis: n = 1 -> a a a a, 2 -> a b b a, 3 -> a b c a.

export const NB = 0xaaaaaaaa;

/** Sequency order of the 64 coefficients (i, j, k) -> i + 4j + 16k: by i+j+k, then i^2+j^2+k^2 (zfp's perm_3). */
export const PERM: readonly number[] = (() => {
  const order: [number, number, number][] = [
    [0, 0, 0],
    [1, 0, 0],
    [0, 1, 0],
    [0, 0, 1],
    [0, 1, 1],
    [1, 0, 1],
    [1, 1, 0],
    [2, 0, 0],
    [0, 2, 0],
    [0, 0, 2],
    [1, 1, 1],
    [2, 1, 0],
    [2, 0, 1],
    [0, 2, 1],
    [1, 2, 0],
    [1, 0, 2],
    [0, 1, 2],
    [3, 0, 0],
    [0, 3, 0],
    [0, 0, 3],
    [2, 1, 1],
    [1, 2, 1],
    [1, 1, 2],
    [0, 2, 2],
    [2, 0, 2],
    [2, 2, 0],
    [3, 1, 0],
    [3, 0, 1],
    [0, 3, 1],
    [1, 3, 0],
    [1, 0, 3],
    [0, 1, 3],
    [1, 2, 2],
    [2, 1, 2],
    [2, 2, 1],
    [3, 1, 1],
    [1, 3, 1],
    [1, 1, 3],
    [3, 2, 0],
    [3, 0, 2],
    [0, 3, 2],
    [2, 3, 0],
    [2, 0, 3],
    [0, 2, 3],
    [2, 2, 2],
    [3, 2, 1],
    [3, 1, 2],
    [1, 3, 2],
    [2, 3, 1],
    [2, 1, 3],
    [1, 2, 3],
    [0, 3, 3],
    [3, 0, 3],
    [3, 3, 0],
    [3, 2, 2],
    [2, 3, 2],
    [2, 2, 3],
    [1, 3, 3],
    [3, 1, 3],
    [3, 3, 1],
    [2, 3, 3],
    [3, 2, 3],
    [3, 3, 2],
    [3, 3, 3],
  ];
  return order.map(([i, j, k]) => i + 4 * j + 16 * k);
})();

// ---------------------------------------------------------------- bit I/O

/** LSB-first reader over 32-bit little-endian words (same bits as zfp's 64-bit words). */
export class BitReader {
  pos: number;
  constructor(
    readonly words: Uint32Array,
    pos = 0,
  ) {
    this.pos = pos;
  }
  readBit(): number {
    const p = this.pos++;
    return (this.words[Math.floor(p / 32)] >>> (p % 32)) & 1;
  }
  /** n <= 32 bits. */
  readBits(n: number): number {
    let v = 0;
    for (let i = 0; i < n; i++) v |= this.readBit() << i;
    return v >>> 0;
  }
}

export class BitWriter {
  pos: number;
  constructor(
    readonly words: Uint32Array,
    pos = 0,
  ) {
    this.pos = pos;
  }
  writeBit(b: number): number {
    const p = this.pos++;
    if (b & 1) this.words[Math.floor(p / 32)] |= 1 << (p % 32);
    return b & 1;
  }
  /** Low n <= 32 bits of v. */
  writeBits(v: number, n: number): void {
    for (let i = 0; i < n; i++) this.writeBit((v >>> i) & 1);
  }
}

// ---------------------------------------------------------------- transforms

function fwdLift(p: Int32Array, o: number, s: number): void {
  let x = p[o],
    y = p[o + s],
    z = p[o + 2 * s],
    w = p[o + 3 * s];
  x = (x + w) | 0;
  x >>= 1;
  w = (w - x) | 0;
  z = (z + y) | 0;
  z >>= 1;
  y = (y - z) | 0;
  x = (x + z) | 0;
  x >>= 1;
  z = (z - x) | 0;
  w = (w + y) | 0;
  w >>= 1;
  y = (y - w) | 0;
  w = (w + (y >> 1)) | 0;
  y = (y - (w >> 1)) | 0;
  p[o] = x;
  p[o + s] = y;
  p[o + 2 * s] = z;
  p[o + 3 * s] = w;
}

function invLift(p: Int32Array, o: number, s: number): void {
  let x = p[o],
    y = p[o + s],
    z = p[o + 2 * s],
    w = p[o + 3 * s];
  y = (y + (w >> 1)) | 0;
  w = (w - (y >> 1)) | 0;
  y = (y + w) | 0;
  w <<= 1;
  w = (w - y) | 0;
  z = (z + x) | 0;
  x <<= 1;
  x = (x - z) | 0;
  y = (y + z) | 0;
  z <<= 1;
  z = (z - y) | 0;
  w = (w + x) | 0;
  x <<= 1;
  x = (x - w) | 0;
  p[o] = x;
  p[o + s] = y;
  p[o + 2 * s] = z;
  p[o + 3 * s] = w;
}

export function fwdXform(p: Int32Array): void {
  for (let z = 0; z < 4; z++) for (let y = 0; y < 4; y++) fwdLift(p, 4 * y + 16 * z, 1);
  for (let x = 0; x < 4; x++) for (let z = 0; z < 4; z++) fwdLift(p, 16 * z + x, 4);
  for (let y = 0; y < 4; y++) for (let x = 0; x < 4; x++) fwdLift(p, x + 4 * y, 16);
}

export function invXform(p: Int32Array): void {
  for (let y = 0; y < 4; y++) for (let x = 0; x < 4; x++) invLift(p, x + 4 * y, 16);
  for (let x = 0; x < 4; x++) for (let z = 0; z < 4; z++) invLift(p, 16 * z + x, 4);
  for (let z = 0; z < 4; z++) for (let y = 0; y < 4; y++) invLift(p, 4 * y + 16 * z, 1);
}

// ---------------------------------------------------------------- block codec

const f32 = new Float32Array(1);
const u32 = new Uint32Array(f32.buffer);

/** frexp exponent of |x| clamped to >= -126, or -127 for 0 (zfp's `exponent`). */
function exponentOf(absMax: number): number {
  if (!(absMax > 0)) return -127;
  f32[0] = absMax;
  const e = (u32[0] >>> 23) & 0xff;
  return e === 0 ? -126 : e - 126;
}

/** C's (int32)(float) as x86 does it: truncation, 0x80000000 for NaN or out of range. */
function castToInt32(v: number): number {
  if (!(Math.abs(v) < 2147483648)) return -2147483648;
  return Math.trunc(v) | 0;
}

/**
 * Encodes one block of 64 float32 values (x + 4y + 16z) with exactly
 * `bitsPerBlock` bits at the writer's position (the words must be zero there).
 */
export function encodeBlock(values: Float32Array, bitsPerBlock: number, w: BitWriter): void {
  const start = w.pos;
  let max = 0;
  for (let i = 0; i < 64; i++) {
    const a = Math.abs(values[i]);
    if (max < a) max = a;
  }
  const emax = exponentOf(max);
  const e = emax + 127;
  if (e === 0) {
    w.writeBit(0);
    w.pos = start + bitsPerBlock;
    return;
  }
  w.writeBits(2 * e + 1, 9);
  const s = Math.fround(2 ** (30 - emax));
  const q = new Int32Array(64);
  for (let i = 0; i < 64; i++) q[i] = castToInt32(Math.fround(s * values[i]));
  fwdXform(q);
  const u = new Uint32Array(64);
  for (let i = 0; i < 64; i++) u[i] = (((q[PERM[i]] >>> 0) + NB) ^ NB) >>> 0;
  let bits = bitsPerBlock - 9;
  let n = 0;
  for (let k = 32; bits > 0 && k-- > 0; ) {
    // bit plane k as two 32-bit halves (coefficients 0..31, 32..63)
    let lo = 0,
      hi = 0;
    for (let i = 0; i < 32; i++) {
      lo |= ((u[i] >>> k) & 1) << i;
      hi |= ((u[i + 32] >>> k) & 1) << i;
    }
    lo >>>= 0;
    hi >>>= 0;
    // the first n bits verbatim
    const m = Math.min(n, bits);
    bits -= m;
    w.writeBits(lo, Math.min(m, 32));
    if (m > 32) w.writeBits(hi, m - 32);
    // remaining bits: x = plane >> m
    let x = m >= 64 ? 0n : ((BigInt(hi) << 32n) | BigInt(lo)) >> BigInt(m);
    for (; bits > 0 && n < 64; x >>= 1n, n++) {
      bits--;
      if (!w.writeBit(x !== 0n ? 1 : 0)) break;
      for (; bits > 0 && n < 63; x >>= 1n, n++) {
        bits--;
        if (w.writeBit(Number(x & 1n))) break;
      }
    }
  }
  w.pos = start + bitsPerBlock;
}

/** Decodes one block (`bitsPerBlock` bits at the reader's position) into 64 float32 bit patterns. */
export function decodeBlock(r: BitReader, bitsPerBlock: number, out: Uint32Array): void {
  const start = r.pos;
  out.fill(0);
  if (!r.readBit()) {
    r.pos = start + bitsPerBlock;
    return;
  }
  const emax = r.readBits(8) - 127;
  let bits = bitsPerBlock - 9;
  const u = new Uint32Array(64);
  let n = 0;
  for (let k = 32; bits > 0 && k-- > 0; ) {
    const m = Math.min(n, bits);
    bits -= m;
    let lo = r.readBits(Math.min(m, 32));
    let hi = m > 32 ? r.readBits(m - 32) : 0;
    for (; n < 64 && bits > 0; n++) {
      bits--;
      if (!r.readBit()) break;
      for (; n < 63 && bits > 0; n++) {
        bits--;
        if (r.readBit()) break;
      }
      if (n < 32) lo = (lo | (1 << n)) >>> 0;
      else hi = (hi | (1 << (n - 32))) >>> 0;
    }
    for (let i = 0; i < 32; i++) {
      if ((lo >>> i) & 1) u[i] |= 1 << k;
      if ((hi >>> i) & 1) u[i + 32] |= 1 << k;
    }
  }
  const q = new Int32Array(64);
  for (let i = 0; i < 64; i++) q[PERM[i]] = (((u[i] ^ NB) >>> 0) - NB) | 0;
  invXform(q);
  const s = Math.fround(2 ** (emax - 30));
  for (let i = 0; i < 64; i++) {
    f32[0] = Math.fround(Math.fround(q[i]) * s);
    out[i] = u32[0];
  }
  r.pos = start + bitsPerBlock;
}

// ---------------------------------------------------------------- volumes

export type Dims3 = readonly [number, number, number];

/** zfp's padding of a partial row of n (1..3) values at stride s. */
function pad(p: Float32Array, o: number, n: number, s: number): void {
  if (n >= 4) return;
  if (n <= 1) p[o + s] = p[o];
  if (n <= 2) p[o + 2 * s] = p[o + s];
  p[o + 3 * s] = p[o];
}

/** Gathers block (bx, by, bz) of a float32 volume (x fastest) with zfp's padding. */
export function gatherBlock(vol: Float32Array, dims: Dims3, bx: number, by: number, bz: number, out: Float32Array): void {
  const [X, Y, Z] = dims;
  const nx = Math.min(4, X - 4 * bx),
    ny = Math.min(4, Y - 4 * by),
    nz = Math.min(4, Z - 4 * bz);
  for (let z = 0; z < nz; z++) {
    for (let y = 0; y < ny; y++) {
      const row = 4 * bx + X * (4 * by + y + Y * (4 * bz + z));
      for (let x = 0; x < nx; x++) out[16 * z + 4 * y + x] = vol[row + x];
      pad(out, 16 * z + 4 * y, nx, 1);
    }
    for (let x = 0; x < 4; x++) pad(out, 16 * z + x, ny, 4);
  }
  for (let y = 0; y < 4; y++) for (let x = 0; x < 4; x++) pad(out, 4 * y + x, nz, 16);
}

/** Blocks in raster order into `words` starting at bit `payloadBit` (words zeroed). */
export function encodeVolume(vol: Float32Array, dims: Dims3, bitsPerBlock: number, words: Uint32Array, payloadBit = 0): void {
  const [bx, by, bz] = dims.map((n) => Math.ceil(n / 4));
  const w = new BitWriter(words, payloadBit);
  const block = new Float32Array(64);
  for (let k = 0; k < bz; k++) {
    for (let j = 0; j < by; j++) {
      for (let i = 0; i < bx; i++) {
        gatherBlock(vol, dims, i, j, k, block);
        encodeBlock(block, bitsPerBlock, w);
      }
    }
  }
}

/** Decodes every block of the stream in `words` (block 0 at bit `payloadBit`) to a float32 volume. */
export function decodeVolume(words: Uint32Array, dims: Dims3, bitsPerBlock: number, payloadBit = 0): Float32Array {
  const [X, Y, Z] = dims;
  const [bx, by, bz] = dims.map((n) => Math.ceil(n / 4));
  const out = new Float32Array(X * Y * Z);
  const outBits = new Uint32Array(out.buffer);
  const r = new BitReader(words, payloadBit);
  const block = new Uint32Array(64);
  for (let k = 0; k < bz; k++) {
    for (let j = 0; j < by; j++) {
      for (let i = 0; i < bx; i++) {
        decodeBlock(r, bitsPerBlock, block);
        for (let z = 0; z < 4 && 4 * k + z < Z; z++) {
          for (let y = 0; y < 4 && 4 * j + y < Y; y++) {
            for (let x = 0; x < 4 && 4 * i + x < X; x++) {
              outBits[4 * i + x + X * (4 * j + y + Y * (4 * k + z))] = block[16 * z + 4 * y + x];
            }
          }
        }
      }
    }
  }
  return out;
}

const FLT_MAX = 3.4028234663852886e38;

/** Per-block [min, max] of the finite values over the voxels inside the volume, raster block order (x fastest). */
export function blockRanges(vol: Float32Array, dims: Dims3): Float32Array {
  const [X, Y, Z] = dims;
  const [bx, by, bz] = dims.map((n) => Math.ceil(n / 4));
  const out = new Float32Array(2 * bx * by * bz);
  let b = 0;
  for (let k = 0; k < bz; k++) {
    for (let j = 0; j < by; j++) {
      for (let i = 0; i < bx; i++, b++) {
        // Non-finite values are skipped; no finite value: the empty range [FLT_MAX, -FLT_MAX] (as the GPU kernel).
        let lo = FLT_MAX,
          hi = -FLT_MAX;
        for (let z = 4 * k; z < Math.min(4 * k + 4, Z); z++) {
          for (let y = 4 * j; y < Math.min(4 * j + 4, Y); y++) {
            for (let x = 4 * i; x < Math.min(4 * i + 4, X); x++) {
              const v = vol[x + X * (y + Y * z)];
              if (!Number.isFinite(v)) continue;
              if (v < lo) lo = v;
              if (v > hi) hi = v;
            }
          }
        }
        out[2 * b] = lo;
        out[2 * b + 1] = hi;
      }
    }
  }
  return out;
}

/** A byte stream as 32-bit words (copied and zero-padded to a whole word). */
export function toWords(bytes: Uint8Array, extraWords = 1): Uint32Array {
  const words = new Uint32Array(Math.ceil(bytes.byteLength / 4) + extraWords);
  new Uint8Array(words.buffer).set(bytes);
  return words;
}
