// What a volume file is, without the GPU: its kind, shape, type, rate and
// what is still missing (a raw file without shape, a header-less stream
// without rate), with sizes checked against the file's length before
// anything is read further. The result carries facts; callers word their
// own prompts (open-volume.ts opens it on the GPU). Errors name the file.
import { detectFile } from '../formats/detect.ts';
import { blockGridOf, fixedRateStreamBytes, MIN_FLOAT_BLOCK_BITS, openZfpStream } from '../zfp/format.ts';
import { DTYPE_BYTES, type DType } from '../core/dtype.ts';
import { formatDims, type Dims } from '../core/naming.ts';
import { NrrdError, parseNrrd, type NrrdVolume } from './nrrd.ts';
import type { TiffVolume } from '../loaders/tiff.ts';

/** The example rate (bits per value) messages suggest; volumes compressed here take the rate chosen from their data (src/zfp/rate-choice.ts). */
export const DEFAULT_RAW_RATE = 8;
/** The name that stands for the built-in volume on the command line. */
export const DEFAULT_VOLUME_NAME = 'default';

export type VolumeFileKind = 'zfp' | 'zfp-headerless' | 'raw' | 'nrrd' | 'tiff';

export class VolumeFileError extends Error {
  constructor(message: string) {
    super(message);
    this.name = 'VolumeFileError';
  }
}

export type MissingField = 'dims' | 'dtype' | 'rate';

/**
 * Who reads the file, for the wording of errors: the page ("not a volume this
 * page reads"; point clouds go to the LIDAR page) or a CLI command.
 */
export type VolumeReader = 'page' | 'command';

export interface InspectOptions {
  reader?: VolumeReader;
}

export interface VolumeFileFacts {
  fileName: string;
  kind: VolumeFileKind;
  bytes: number;
  /** From the header or the name. */
  dims?: Dims;
  /** Sample type of the data in the file (zfp streams: float32). */
  dtype?: DType;
  /** zfp streams: the stream's rate when known. */
  rate?: number;
  /** Header-less zfp without a rate: rates whose stream has exactly this size. */
  fittingRates?: number[];
  /** What must be given before the file can be opened. */
  missing: MissingField[];
  /** Raw and NRRD: compressed here, so a rate is chosen (default DEFAULT_RAW_RATE). */
  compresses: boolean;
  nrrd?: NrrdVolume;
  /** TIFF: the samples, converted to a type the encoder takes. */
  samples?: Uint8Array;
  /** TIFF stacks: the files, in stack order. */
  files?: string[];
  /** World size of a voxel along x, y, z, when the file gives it (NRRD spacings, ImageJ calibration). */
  spacing?: [number, number, number];
}

export function fittingRates(dims: Dims, bytes: number): number[] {
  const g = blockGridOf(dims);
  const blocks = g[0] * g[1] * g[2];
  const out: number[] = [];
  const lo = Math.max(MIN_FLOAT_BLOCK_BITS, Math.floor(((bytes - 8) * 8) / blocks));
  for (let bits = lo; bits <= Math.ceil((bytes * 8) / blocks) && bits <= 0x8000; bits++) {
    if (fixedRateStreamBytes(blocks, bits) === bytes) out.push(bits / 64);
  }
  return out;
}

export function sizeOf(dims: Dims, dtype: DType): number {
  return dims[0] * dims[1] * dims[2] * DTYPE_BYTES[dtype];
}

/** Dimensions from a name or a form: whole numbers from 1 up, or a VolumeFileError naming the file. */
export function checkNamedDims(fileName: string, dims: Dims, where: string): void {
  if (dims.some((n) => !Number.isSafeInteger(n) || n < 1)) {
    throw new VolumeFileError(
      `${fileName}: the shape ${formatDims(dims)} ${where} is impossible: every dimension must be a whole number from 1 up`,
    );
  }
}

/**
 * The value range of an opened volume (Isosurface.info.valueRange, from the
 * GPU's block ranges, which skip NaN and Inf): a VolumeFileError naming the
 * file when the volume has no finite value, so the page and the CLI refuse it
 * instead of offering isovalues in [Infinity, -Infinity].
 */
export function checkValueRange(fileName: string, range: readonly [number, number]): [number, number] {
  const [lo, hi] = range;
  if (!(Number.isFinite(lo) && Number.isFinite(hi) && lo <= hi && Math.abs(lo) < 3.4e38 && Math.abs(hi) < 3.4e38)) {
    throw new VolumeFileError(
      `${fileName}: the volume has no finite values (every decoded value is NaN or infinite): there is no surface to draw`,
    );
  }
  return [lo, hi];
}

/** Says what a file is and what is missing; throws (naming the file) when it cannot be a volume. */
export async function inspectVolumeFile(fileName: string, bytes: Uint8Array, opts: InspectOptions = {}): Promise<VolumeFileFacts> {
  const reader = opts.reader ?? 'page';
  const detected = detectFile(fileName, bytes.subarray(0, 64));
  const name = detected.name;
  const base = { fileName, bytes: bytes.byteLength };
  switch (detected.kind) {
    case 'zfp': {
      const info = openZfpStream(bytes, fileName); // throws ZfpFormatError naming the file
      return { ...base, kind: 'zfp', dims: info.dims, dtype: 'float32', rate: info.rate, missing: [], compresses: false };
    }
    case 'zfp-headerless': {
      if (name.dtype && name.dtype !== 'float32') {
        throw new VolumeFileError(`${fileName}: the name says ${name.dtype}; only float32 zfp streams are supported`);
      }
      const facts: VolumeFileFacts = {
        ...base,
        kind: 'zfp-headerless',
        dtype: 'float32',
        dims: name.dims,
        rate: name.rate,
        missing: [],
        compresses: false,
      };
      if (name.dims) checkNamedDims(fileName, name.dims, 'in the name');
      if (!name.dims) facts.missing.push('dims');
      if (name.rate === undefined) {
        if (name.dims) {
          facts.fittingRates = fittingRates(name.dims, bytes.byteLength);
          // No fixed rate fits: the codec says why (e.g. a fixed-precision stream).
          if (facts.fittingRates.length === 0) openZfpStream(bytes, fileName);
        }
        facts.missing.push('rate');
      } else if (name.dims) {
        openZfpStream(bytes, fileName); // size check now, before asking anything
      }
      return facts;
    }
    case 'raw': {
      const facts: VolumeFileFacts = { ...base, kind: 'raw', dims: name.dims, dtype: name.dtype, missing: [], compresses: true };
      if (name.dims) checkNamedDims(fileName, name.dims, 'in the name');
      if (!name.dims) facts.missing.push('dims');
      if (!name.dtype) facts.missing.push('dtype');
      if (name.dims && name.dtype && sizeOf(name.dims, name.dtype) !== bytes.byteLength) {
        throw new VolumeFileError(
          `${fileName}: ${formatDims(name.dims)} ${name.dtype} is ${sizeOf(name.dims, name.dtype)} bytes, the file has ${bytes.byteLength}; ` +
            "the name must give the volume's shape and type (name_XxYxZ_dtype.raw)",
        );
      }
      return facts;
    }
    case 'nrrd': {
      let nrrd: NrrdVolume;
      try {
        nrrd = await parseNrrd(bytes);
      } catch (e) {
        if (e instanceof NrrdError) throw new VolumeFileError(`${fileName}: ${e.message}`);
        throw e;
      }
      return { ...base, kind: 'nrrd', dims: nrrd.dims, dtype: nrrd.dtype, missing: [], compresses: true, nrrd, spacing: nrrd.spacing };
    }
    case 'tiff':
      return inspectTiffStack([{ name: fileName, bytes }]);
    case 'las':
    case 'laz':
      throw new VolumeFileError(
        reader === 'page'
          ? `${fileName}: this is a ${detected.kind.toUpperCase()} point cloud, not a volume; open it in the LIDAR example page`
          : `${fileName}: this is a ${detected.kind.toUpperCase()} point cloud, not a volume this command reads (\`cli las\` describes it)`,
      );
    case 'swc':
      throw new VolumeFileError(
        `${fileName}: this is an SWC neuron tracing, not a volume${reader === 'page' ? '; open it in the neuron example page' : ''}`,
      );
    default:
      throw new VolumeFileError(
        `${fileName}: not a volume this ${reader} reads (${detected.why}). Supported: .zfp (with header, or named name_XxYxZ_float32.raw.crateR.zfp), ` +
          'name_XxYxZ_dtype.raw (uint8, int8, uint16, int16, float32, float64), .nrrd and TIFF stacks',
      );
  }
}

/**
 * A TIFF stack (one multi-page file, or single-page files ordered by name) as
 * a volume: x, y from the pages, z = page. One sample per pixel; 32-bit
 * integer samples become float64 (the encoder's widest exact type).
 */
export async function inspectTiffStack(sources: { name: string; bytes: Uint8Array | Blob }[]): Promise<VolumeFileFacts> {
  const { loadTiffStack, TiffError } = await import('../loaders/tiff.ts');
  const fileName = sources.length === 1 ? sources[0].name : `${sources[0].name} … (${sources.length} files)`;
  let v: TiffVolume;
  try {
    v = await loadTiffStack(sources);
  } catch (e) {
    if (e instanceof TiffError) throw new VolumeFileError(e.message);
    throw e;
  }
  const bytes = sources.reduce((n, s) => n + (s.bytes instanceof Blob ? s.bytes.size : s.bytes.byteLength), 0);
  return tiffVolumeFacts(fileName, v, bytes);
}

export interface TiffFactsOptions {
  /**
   * Several samples per pixel: refuse (the default; an isosurface of colour
   * makes no sense) or take their mean as float32 (what the neuron page's
   * volume rendering shows of multi-channel stacks).
   */
  channels?: 'refuse' | 'mean';
}

/**
 * The facts of a TIFF stack already decoded by libtiff (src/loaders/tiff.ts),
 * so a page that shows the stack itself compresses the same samples without
 * decoding the files again. The samples are shared with `v` where their type
 * needs no conversion (layout [page][y][x] = voxel (x, y, z), x fastest, as
 * the encoder takes it).
 */
export function tiffVolumeFacts(fileName: string, v: TiffVolume, bytes: number, opts: TiffFactsOptions = {}): VolumeFileFacts {
  const channels = v.samplesPerPixel;
  let dtype: DType;
  let data: ArrayBufferView;
  if (channels !== 1) {
    if (opts.channels !== 'mean') {
      throw new VolumeFileError(
        `${fileName}: ${channels} samples per pixel (colour); an isosurface needs one value per voxel (save a single channel)`,
      );
    }
    const n = v.data.length / channels;
    const mean = new Float32Array(n);
    for (let i = 0; i < n; i++) {
      let s = 0;
      for (let c = 0; c < channels; c++) s += v.data[i * channels + c];
      mean[i] = s / channels;
    }
    dtype = 'float32';
    data = mean;
  } else if (v.dtype === 'uint32' || v.dtype === 'int32') {
    dtype = 'float64';
    data = Float64Array.from(v.data as ArrayLike<number>);
  } else {
    dtype = v.dtype;
    data = v.data;
  }
  const samples = new Uint8Array(data.buffer, data.byteOffset, data.byteLength);
  return { fileName, kind: 'tiff', bytes, dims: v.dims, dtype, missing: [], compresses: true, samples, files: v.files, spacing: v.spacing };
}

/** The rate `rate` is a usable zfp rate (checked before compressing). */
export function checkRate(fileName: string, rate: number | undefined): number {
  if (rate === undefined || !Number.isFinite(rate) || rate <= 0)
    throw new VolumeFileError(`${fileName}: give a positive rate (bits per value), e.g. ${DEFAULT_RAW_RATE}`);
  return rate;
}
