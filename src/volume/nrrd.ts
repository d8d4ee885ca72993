// NRRD volumes (teem's format, written by 3D Slicer, ITK, VTK): a text header
// ("NRRD000N", "field: value" lines, a blank line) followed by the samples.
// We read attached data with raw or gzip encoding, 3 dimensions (or 4 with a
// leading axis of size 1), and the scalar types the compressor accepts.

import { DTYPE_BYTES, type DType } from '../core/dtype.ts';
import type { Dims } from '../core/naming.ts';

export class NrrdError extends Error {
  constructor(message: string) {
    super(message);
    this.name = 'NrrdError';
  }
}

export interface NrrdVolume {
  dims: Dims;
  dtype: DType;
  /** Samples, little-endian, x fastest (converted from big-endian if needed). */
  data: Uint8Array;
  /** Voxel spacing when the header gives it (spacings or space directions). */
  spacing?: [number, number, number];
  fields: Record<string, string>;
}

const TYPE_NAMES: Record<string, DType> = {
  'signed char': 'int8',
  int8: 'int8',
  int8_t: 'int8',
  uchar: 'uint8',
  'unsigned char': 'uint8',
  uint8: 'uint8',
  uint8_t: 'uint8',
  short: 'int16',
  'short int': 'int16',
  'signed short': 'int16',
  'signed short int': 'int16',
  int16: 'int16',
  int16_t: 'int16',
  ushort: 'uint16',
  'unsigned short': 'uint16',
  'unsigned short int': 'uint16',
  uint16: 'uint16',
  uint16_t: 'uint16',
  float: 'float32',
  double: 'float64',
};

/** Finds the end of the header: the first empty line. Returns the data offset. */
function headerEnd(bytes: Uint8Array): number {
  const limit = Math.min(bytes.length, 1 << 16);
  for (let i = 0; i < limit; i++) {
    if (bytes[i] === 0x0a && bytes[i + 1] === 0x0a) return i + 2;
    if (bytes[i] === 0x0a && bytes[i + 1] === 0x0d && bytes[i + 2] === 0x0a) return i + 3;
  }
  throw new NrrdError('no end of header (a blank line) in the first 64 KiB');
}

export function parseNrrdHeader(bytes: Uint8Array): { fields: Record<string, string>; dataOffset: number } {
  const magic = String.fromCharCode(...bytes.subarray(0, 8));
  if (!/^NRRD000\d$/.test(magic)) throw new NrrdError('not a NRRD file (no "NRRD000x" magic)');
  const dataOffset = headerEnd(bytes);
  const text = new TextDecoder().decode(bytes.subarray(0, dataOffset));
  const fields: Record<string, string> = {};
  for (const raw of text.split(/\r?\n/).slice(1)) {
    const line = raw.trim();
    if (line === '' || line.startsWith('#')) continue;
    const m = /^([^:]+):=?\s*(.*)$/.exec(line);
    if (m) fields[m[1].trim().toLowerCase()] = m[2].trim();
  }
  return { fields, dataOffset };
}

function parseSpacing(fields: Record<string, string>, axes: number): [number, number, number] | undefined {
  if (fields.spacings) {
    const s = fields.spacings.split(/\s+/).map(Number).slice(-3);
    if (s.length === 3 && s.every((v) => Number.isFinite(v) && v > 0)) return s as [number, number, number];
  }
  const dirs = fields['space directions'];
  if (dirs) {
    const vectors = [...dirs.matchAll(/\(([^)]*)\)/g)].map((m) => m[1].split(',').map(Number));
    const lengths = vectors.slice(-axes).map((v) => Math.hypot(...v));
    if (lengths.length === 3 && lengths.every((v) => Number.isFinite(v) && v > 0)) return lengths as [number, number, number];
  }
  return undefined;
}

/** Largest sample data this reader takes (bytes): the page holds the samples in memory before compressing them. */
export const NRRD_MAX_DATA_BYTES = 2 ** 32;

/**
 * Inflates a gzip payload, stopping as soon as `need` bytes are out (the rest
 * is ignored, as for raw data): a gzip bomb costs at most `need` bytes.
 * Memory grows with what actually comes out, not with what the header claims.
 * DecompressionStream: in browsers and in Node (>= 18) alike.
 */
async function gunzipPrefix(bytes: Uint8Array, need: number): Promise<Uint8Array> {
  // Feed the input in slices so inflating never runs far ahead of the reads.
  const slice = 1 << 16;
  let at = 0;
  const input = new ReadableStream<BufferSource>({
    pull(controller) {
      if (at >= bytes.length) controller.close();
      else {
        controller.enqueue(bytes.slice(at, at + slice));
        at += slice;
      }
    },
  });
  const reader = input.pipeThrough(new DecompressionStream('gzip')).getReader();
  let out = new Uint8Array(Math.min(need, Math.max(1 << 16, bytes.length * 4)));
  let filled = 0;
  try {
    while (filled < need) {
      const { done, value } = await reader.read();
      if (done) break;
      const take = Math.min(value.length, need - filled);
      if (filled + take > out.length) {
        const grown = new Uint8Array(Math.min(need, Math.max(out.length * 2, filled + take)));
        grown.set(out.subarray(0, filled));
        out = grown;
      }
      out.set(value.subarray(0, take), filled);
      filled += take;
    }
  } catch (e) {
    const why = e instanceof Error ? e.message : String(e);
    throw new NrrdError(`the gzip data is damaged after ${filled} of ${need} bytes (${why})`);
  } finally {
    reader.cancel().catch(() => {});
  }
  return out.subarray(0, filled);
}

/** What a NRRD header says about its samples (attached data, 3-D, a type the compressor takes). */
export interface NrrdLayout {
  dims: Dims;
  dtype: DType;
  gzip: boolean;
  bigEndian: boolean;
  /** Bytes of samples (checked against NRRD_MAX_DATA_BYTES). */
  need: number;
  spacing?: [number, number, number];
}

/** The samples' layout from a header's fields; throws NrrdError with the reason. */
export function nrrdLayout(fields: Record<string, string>): NrrdLayout {
  if (fields['data file'] || fields.datafile)
    throw new NrrdError('detached data files (.nhdr + data file) are not supported; save as a single .nrrd');
  const typeName = (fields.type ?? '').toLowerCase();
  const dtype = TYPE_NAMES[typeName];
  if (!dtype)
    throw new NrrdError(`sample type "${fields.type ?? '(missing)'}" is not supported (use uint8, int8, uint16, int16, float or double)`);
  const sizes = (fields.sizes ?? '')
    .split(/\s+/)
    .filter((s) => s !== '')
    .map(Number);
  const dimension = Number(fields.dimension);
  if (sizes.length !== dimension || sizes.some((s) => !Number.isInteger(s) || s < 1)) {
    throw new NrrdError(`bad "sizes: ${fields.sizes ?? ''}" for dimension ${fields.dimension ?? '(missing)'}`);
  }
  // A leading axis of length 1 (a scalar "component" axis) is allowed.
  const spatial = sizes.length === 4 && sizes[0] === 1 ? sizes.slice(1) : sizes;
  if (spatial.length !== 3) throw new NrrdError(`only 3D volumes are supported (this file has ${sizes.length} axes: ${sizes.join(' x ')})`);
  const dims = spatial as Dims;
  const encoding = (fields.encoding ?? '').toLowerCase();
  const gzip = encoding === 'gzip' || encoding === 'gz';
  if (!gzip && encoding !== 'raw') throw new NrrdError(`encoding "${fields.encoding ?? '(missing)'}" is not supported (raw or gzip)`);
  const width = DTYPE_BYTES[dtype];
  // Sizes are integers < 2^53 each; the product is checked before anything is allocated.
  const need = dims[0] * dims[1] * dims[2] * width;
  if (!(need <= NRRD_MAX_DATA_BYTES)) {
    throw new NrrdError(
      `${dims.join('x')} ${dtype} is ${need} bytes of samples, more than the ${NRRD_MAX_DATA_BYTES} bytes (4 GiB) this reader takes`,
    );
  }
  const bigEndian = (fields.endian ?? 'little').toLowerCase() === 'big' && width > 1;
  return { dims, dtype, gzip, bigEndian, need, spacing: parseSpacing(fields, 3) };
}

/** Parses a NRRD file with attached data; throws NrrdError with the reason. */
export async function parseNrrd(bytes: Uint8Array): Promise<NrrdVolume> {
  const { fields, dataOffset } = parseNrrdHeader(bytes);
  const { dims, dtype, gzip, bigEndian, need, spacing } = nrrdLayout(fields);
  const width = DTYPE_BYTES[dtype];
  const stored = bytes.subarray(dataOffset);
  const payload = gzip ? await gunzipPrefix(stored, need) : stored;
  if (payload.length < need) {
    throw new NrrdError(
      `truncated: ${dims.join('x')} ${dtype} needs ${need} bytes of data, the file has ${payload.length}${gzip ? ' (after gunzip)' : ''}`,
    );
  }
  const data = payload.length === need && gzip ? payload : payload.slice(0, need);
  if (bigEndian) {
    for (let i = 0; i < data.length; i += width) data.subarray(i, i + width).reverse();
  }
  return { dims, dtype, data, spacing, fields };
}
