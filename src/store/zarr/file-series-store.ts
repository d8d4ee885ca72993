// A time series of volume files (src/volume/series-files.ts: raw, NRRD or
// TIFF stacks, one file per time point, checked) seen as a read-only Zarr
// store, so the page plays it with the one store engine (openStore: a store
// of lossless chunks with an OME `t` axis): an OME-Zarr 0.4 group (Zarr v2)
// of one level, a 4-D array [T, Z, Y, X] of the files' type, little endian,
// uncompressed, in chunks [1, cz, Y, X] (slabs of z planes within
// SLAB_BYTES; the last slab of a time point padded with the fill value 0 as
// Zarr wants it), so a chunk of a raw file is one byte range of it. Nothing
// of a file is read before one of its chunks is asked for.
import type { AbsolutePath, AsyncReadable, RangeQuery } from '@zarrita/storage';
import { SERIES_DTYPE_BYTES, type SeriesDType, type SeriesFiles } from '../../volume/series-files.ts';

/** A chunk holds at most this many bytes (one z plane when a plane is larger). */
export const SLAB_BYTES = 16 * 2 ** 20;

const V2_DTYPE: Record<SeriesDType, string> = {
  uint8: '|u1',
  int8: '|i1',
  uint16: '<u2',
  int16: '<i2',
  uint32: '<u4',
  int32: '<i4',
  float32: '<f4',
  float64: '<f8',
};

/**
 * Z planes per chunk: as many as fit in `slabBytes`, a multiple of 64 (the
 * page's brick edge) when 64 fit, else a power of two (so a brick's planes
 * come from whole chunks), the whole volume when it fits.
 */
export function slabPlanes(dims: readonly [number, number, number], bytesPerValue: number, slabBytes = SLAB_BYTES): number {
  const plane = dims[0] * dims[1] * bytesPerValue;
  const fit = Math.max(1, Math.floor(slabBytes / plane));
  if (fit >= dims[2]) return dims[2];
  if (fit >= 64) return fit - (fit % 64);
  return 2 ** Math.floor(Math.log2(fit));
}

const json = (v: unknown) => new TextEncoder().encode(JSON.stringify(v));

export class FileSeriesStore implements AsyncReadable {
  /** Z planes per chunk. */
  readonly planes: number;
  readonly #meta: Map<string, Uint8Array>;
  readonly #plane: number;
  /** Chunks read (tests). */
  chunksRead = 0;

  constructor(
    readonly series: SeriesFiles,
    /** Shown in messages and the Store panel. */
    readonly name: string,
    slabBytes = SLAB_BYTES,
  ) {
    const [x, y, z] = series.dims;
    const bpv = SERIES_DTYPE_BYTES[series.dtype];
    this.planes = slabPlanes(series.dims, bpv, slabBytes);
    this.#plane = x * y * bpv;
    const [sx, sy, sz] = series.spacing ?? [1, 1, 1];
    const axes = [
      { name: 't', type: 'time' },
      { name: 'z', type: 'space' },
      { name: 'y', type: 'space' },
      { name: 'x', type: 'space' },
    ];
    const multiscale = {
      version: '0.4',
      name,
      axes,
      datasets: [{ path: '0', coordinateTransformations: [{ type: 'scale', scale: [1, sz, sy, sx] }] }],
    };
    this.#meta = new Map([
      ['/.zgroup', json({ zarr_format: 2 })],
      ['/.zattrs', json({ multiscales: [multiscale] })],
      [
        '/0/.zarray',
        json({
          zarr_format: 2,
          shape: [series.names.length, z, y, x],
          chunks: [1, this.planes, y, x],
          dtype: V2_DTYPE[series.dtype],
          compressor: null,
          filters: null,
          fill_value: 0,
          order: 'C',
          dimension_separator: '.',
        }),
      ],
      ['/0/.zattrs', json({})],
    ]);
  }

  async get(key: AbsolutePath): Promise<Uint8Array | undefined> {
    const meta = this.#meta.get(key);
    if (meta) return meta.slice();
    const m = /^\/0\/(\d+)\.(\d+)\.0\.0$/.exec(key);
    if (!m) return undefined;
    const t = Number(m[1]);
    const c = Number(m[2]);
    const z = this.series.dims[2];
    if (!(t < this.series.names.length) || !(c * this.planes < z)) return undefined;
    const z0 = c * this.planes;
    const nz = Math.min(this.planes, z - z0);
    const bytes = await this.series.readPlanes(t, z0, nz);
    this.chunksRead++;
    if (nz === this.planes) return bytes;
    // the last slab: the rest of the chunk is the fill value (0)
    const chunk = new Uint8Array(this.planes * this.#plane);
    chunk.set(bytes);
    return chunk;
  }

  async getRange(key: AbsolutePath, range: RangeQuery): Promise<Uint8Array | undefined> {
    const all = await this.get(key);
    if (!all) return undefined;
    if ('suffixLength' in range) return all.slice(Math.max(0, all.length - range.suffixLength));
    return all.slice(range.offset, range.offset + range.length);
  }
}
