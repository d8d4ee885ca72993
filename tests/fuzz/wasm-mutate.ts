// Seeded mutations of LAS/LAZ and TIFF files: truncations, bit flips and
// header fields set to extremes (0, 1, 2^31-1, 2^32-1, 2^63, NaN, ...), at
// the fields each format's readers allocate from.
export type Rand = () => number;

const pick = <T>(rand: Rand, xs: readonly T[]): T => xs[Math.floor(rand() * xs.length)];

const U8 = [0, 1, 0x7f, 0xff] as const;
const U16 = [0, 1, 0x7fff, 0x8000, 0xffff] as const;
const U32 = [0, 1, 0x7fff_ffff, 0x8000_0000, 0xffff_ffff, 65537, 32768] as const;
const U64 = [0n, 1n, 0x7fff_ffffn, 0xffff_ffffn, 1n << 32n, 1n << 63n, (1n << 64n) - 1n, (1n << 62n) / 16388n] as const;
const F64 = [0, -0, NaN, Infinity, -Infinity, 1e308, -1e308, 5e-324, -1] as const;

type Width = 'u8' | 'u16' | 'u32' | 'u64' | 'f64';

function write(bytes: Uint8Array, at: number, width: Width, rand: Rand, littleEndian = true): string {
  const size = { u8: 1, u16: 2, u32: 4, u64: 8, f64: 8 }[width];
  if (at < 0 || at + size > bytes.length) return 'out of range';
  const v = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  switch (width) {
    case 'u8': {
      const x = pick(rand, U8);
      v.setUint8(at, x);
      return String(x);
    }
    case 'u16': {
      const x = pick(rand, U16);
      v.setUint16(at, x, littleEndian);
      return String(x);
    }
    case 'u32': {
      const x = pick(rand, U32);
      v.setUint32(at, x, littleEndian);
      return String(x);
    }
    case 'u64': {
      const x = pick(rand, U64);
      v.setBigUint64(at, x, littleEndian);
      return String(x);
    }
    case 'f64': {
      const x = pick(rand, F64);
      v.setFloat64(at, x, littleEndian);
      return String(x);
    }
  }
}

export function truncate(seed: Uint8Array, rand: Rand): { bytes: Uint8Array; what: string } {
  // Mostly inside the headers (the first 1 KiB), sometimes anywhere.
  const n = rand() < 0.5 ? Math.floor(rand() * Math.min(seed.length, 1024)) : Math.floor(rand() * seed.length);
  return { bytes: seed.slice(0, n), what: `truncated to ${n} bytes` };
}

export function flipBits(seed: Uint8Array, rand: Rand): { bytes: Uint8Array; what: string } {
  const bytes = seed.slice();
  const flips = 1 + Math.floor(rand() * 8);
  // Headers, the start of the data, or the end (LAZ chunk tables live there).
  const region = pick(rand, ['head', 'any', 'tail'] as const);
  for (let i = 0; i < flips; i++) {
    const at =
      region === 'head'
        ? Math.floor(rand() * Math.min(bytes.length, 512))
        : region === 'tail'
          ? bytes.length - 1 - Math.floor(rand() * Math.min(bytes.length, 256))
          : Math.floor(rand() * bytes.length);
    bytes[at] ^= 1 << Math.floor(rand() * 8);
  }
  return { bytes, what: `${flips} bit flips (${region})` };
}

// ---------------------------------------------------------------- LAS

const LAS_FIELDS: [string, number, Width][] = [
  ['version major', 24, 'u8'],
  ['version minor', 25, 'u8'],
  ['header size', 94, 'u16'],
  ['offset to point data', 96, 'u32'],
  ['VLR count', 100, 'u32'],
  ['point format', 104, 'u8'],
  ['record length', 105, 'u16'],
  ['legacy point count', 107, 'u32'],
  ['x scale', 131, 'f64'],
  ['y scale', 139, 'f64'],
  ['z scale', 147, 'f64'],
  ['x offset', 155, 'f64'],
  ['z offset', 171, 'f64'],
  ['max x', 179, 'f64'],
  ['min x', 187, 'f64'],
  ['max z', 211, 'f64'],
  ['min z', 219, 'f64'],
  ['waveform start', 227, 'u64'],
  ['EVLR start', 235, 'u64'],
  ['EVLR count', 243, 'u32'],
  ['extended point count', 247, 'u64'],
];

export function lasField(seed: Uint8Array, rand: Rand): { bytes: Uint8Array; what: string } {
  const bytes = seed.slice();
  const dv = new DataView(bytes.buffer);
  const headerSize = bytes.length >= 96 ? dv.getUint16(94, true) : 227;
  const offset = bytes.length >= 100 ? dv.getUint32(96, true) : 0;
  const choice = rand();
  if (choice < 0.15 && headerSize + 54 <= bytes.length) {
    // The first VLR's payload length, or (LAZ) a field of LASzip's own VLR.
    const at = pick(rand, [headerSize + 20, headerSize + 54 + 12, headerSize + 54 + 16, headerSize + 54 + 32, headerSize + 54 + 34]);
    const width = at === headerSize + 20 || at >= headerSize + 54 + 32 ? 'u16' : 'u32';
    return { bytes, what: `VLR field at ${at} = ${write(bytes, at, width, rand)}` };
  }
  if (choice < 0.25 && offset + 8 <= bytes.length) {
    // LAZ: the pointer to the chunk table, at the start of the point data.
    return { bytes, what: `chunk table pointer = ${write(bytes, offset, 'u64', rand)}` };
  }
  const [name, at, width] = pick(rand, LAS_FIELDS);
  return { bytes, what: `${name} = ${write(bytes, at, width, rand)}` };
}

// ---------------------------------------------------------------- TIFF

/** Byte positions of the entries of the first few IFDs of a classic TIFF. */
function tiffEntries(bytes: Uint8Array): { le: boolean; ifds: number[]; entries: number[] } {
  const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const le = bytes[0] === 0x49;
  const ifds: number[] = [];
  const entries: number[] = [];
  if (bytes.length < 8 || dv.getUint16(2, le) !== 42) return { le, ifds, entries };
  let at = dv.getUint32(4, le);
  for (let i = 0; i < 8 && at > 0 && at + 2 <= bytes.length; i++) {
    ifds.push(at);
    const n = dv.getUint16(at, le);
    for (let e = 0; e < n && at + 2 + 12 * (e + 1) <= bytes.length; e++) entries.push(at + 2 + 12 * e);
    if (at + 2 + 12 * n + 4 > bytes.length) break;
    at = dv.getUint32(at + 2 + 12 * n, le);
  }
  return { le, ifds, entries };
}

const SIZE_TAGS = new Set([256, 257, 258, 277, 278, 322, 323, 273, 279, 324, 325, 259, 284, 339]);

export function tiffField(seed: Uint8Array, rand: Rand): { bytes: Uint8Array; what: string } {
  const bytes = seed.slice();
  const dv = new DataView(bytes.buffer);
  const { le, ifds, entries } = tiffEntries(bytes);
  if (entries.length === 0) return flipBits(seed, rand);
  const choice = rand();
  if (choice < 0.1) {
    const at = pick(rand, ifds);
    return { bytes, what: `IFD entry count = ${write(bytes, at, 'u16', rand, le)}` };
  }
  if (choice < 0.15) return { bytes, what: `first IFD offset = ${write(bytes, 4, 'u32', rand, le)}` };
  // Mostly the tags readers size things from.
  const sized = entries.filter((e) => SIZE_TAGS.has(dv.getUint16(e, le)));
  const entry = sized.length > 0 && rand() < 0.8 ? pick(rand, sized) : pick(rand, entries);
  const tag = dv.getUint16(entry, le);
  const type = dv.getUint16(entry + 2, le);
  const part = rand();
  if (part < 0.15) return { bytes, what: `tag ${tag} type = ${write(bytes, entry + 2, 'u16', rand, le)}` };
  if (part < 0.4) return { bytes, what: `tag ${tag} count = ${write(bytes, entry + 4, 'u32', rand, le)}` };
  if (type === 3 && dv.getUint32(entry + 4, le) === 1)
    return { bytes, what: `tag ${tag} value = ${write(bytes, entry + 8, 'u16', rand, le)}` };
  return { bytes, what: `tag ${tag} value/offset = ${write(bytes, entry + 8, 'u32', rand, le)}` };
}

/** The TIFF class of issue 13: a 32768 x 65537 uint16 page (2^32 + 64 KiB bytes). */
export function hugeTiffPage(seed: Uint8Array): Uint8Array {
  const bytes = seed.slice();
  const dv = new DataView(bytes.buffer);
  const { le, entries } = tiffEntries(bytes);
  for (const e of entries) {
    const tag = dv.getUint16(e, le);
    if (tag !== 256 && tag !== 257) continue;
    dv.setUint16(e + 2, 4, le); // LONG
    dv.setUint32(e + 4, 1, le);
    dv.setUint32(e + 8, tag === 256 ? 32768 : 65537, le);
  }
  return bytes;
}
