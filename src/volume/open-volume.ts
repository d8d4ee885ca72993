// From a file's bytes (or the built-in default volume) to a fixed-rate zfp
// stream on the GPU: the one path the page, the CLI (extract, bench), the
// benchmarks and the tests share, so they compute the same surfaces for the
// same input.
//
//   zfp with header       -> validated and uploaded as is
//   header-less .zfp       -> shape and rate from the name (or given), uploaded
//   name_XxYxZ_dtype.raw   -> compressed on the GPU at the chosen rate
//   .nrrd (raw or gzip)    -> compressed on the GPU at the chosen rate
//   TIFF stack             -> read by libtiff (Wasm, src/loaders/tiff.ts), compressed likewise
//   "default"              -> generated (procedural.ts), compressed at DEFAULT_VOLUME_RATE
//
// inspectVolumeFile says what a file is and what is still missing (a raw
// file without shape, a header-less stream without rate) so a caller can ask
// for it; openVolumeFile does the work. openVolumeBytes does both for callers
// that cannot ask (the CLI: what is missing must come with the call).
// Errors name the file.

import { detectFile } from '../formats/detect.ts';
import { blockGridOf, fixedRateStreamBytes, MIN_FLOAT_BLOCK_BITS, openZfpStream } from '../zfp/format.ts';
import { ZfpFormatError } from '../zfp/header.ts';
import { loadZfpStream, type ZfpGpuStream } from '../zfp/gpu-stream.ts';
import { ZfpEncoder } from '../zfp/encoder.ts';
import { DTYPE_BYTES, type DType } from '../core/dtype.ts';
import { formatDims, parseVolumeName, type Dims } from '../core/naming.ts';
import { NrrdError, parseNrrd, type NrrdVolume } from './nrrd.ts';
import { allNonFiniteMessage, countNonFinite, nonFiniteNotice, nonFiniteTotal, replaceNonFinite, type NonFiniteCount } from './non-finite.ts';
import { generateDefaultVolume } from './procedural.ts';
import type { TiffVolume } from '../loaders/tiff.ts';

/** Rate (bits per value) raw volumes are compressed at unless the user picks another. */
export const DEFAULT_RAW_RATE = 8;
/** Rate of the built-in default volume (page and `cli ... default`). */
export const DEFAULT_VOLUME_RATE = 8;
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

export interface OpenRequest {
  dims?: Dims;
  dtype?: DType;
  /** Header-less zfp: the stream's rate. Raw/NRRD: the rate to compress at. */
  rate?: number;
}

export type OpenPhase = 'upload' | 'compress';

export interface OpenedVolume {
  stream: ZfpGpuStream;
  /** Short name for display (file name, or the default volume's name). */
  name: string;
  fileName: string;
  kind: VolumeFileKind | 'default';
  dims: Dims;
  /** Type of the original samples (what was compressed, or float32 for zfp). */
  sourceDtype: DType;
  /** Bytes of the input as given (file size, or the generated data). */
  sourceBytes: number;
  /** Bytes of the compressed stream on the GPU. */
  compressedBytes: number;
  rate: number;
  /** True when the page/CLI compressed the volume (raw, NRRD, default). */
  compressedHere: boolean;
  /** The default volume's suggested isovalue. */
  defaultIsovalue?: number;
  /** World size of a voxel along x, y, z, when the file gives it. */
  spacing?: [number, number, number];
  /** What the user should know about the file (non-finite values replaced, bytes ignored), one sentence each. */
  notes: string[];
  /** Float volumes compressed here: NaN/Inf counts (replaced before compression, see non-finite.ts). */
  nonFinite?: NonFiniteCount;
}

export interface OpenOptions {
  /** Reused between calls (pipelines compile once); created when absent. */
  encoder?: ZfpEncoder;
  onPhase?: (phase: OpenPhase) => void;
}

const encoders = new WeakMap<GPUDevice, Promise<ZfpEncoder>>();

/** One encoder per device, created on first use. */
export function encoderFor(device: GPUDevice): Promise<ZfpEncoder> {
  let e = encoders.get(device);
  if (!e) {
    e = ZfpEncoder.create(device);
    e.catch(() => encoders.delete(device));
    encoders.set(device, e);
  }
  return e;
}

/** Rates (multiples of 1/64) whose header-less stream of `dims` is exactly `bytes` long. */
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

function sizeOf(dims: Dims, dtype: DType): number {
  return dims[0] * dims[1] * dims[2] * DTYPE_BYTES[dtype];
}

/** Dimensions from a name or a form: whole numbers from 1 up, or a VolumeFileError naming the file. */
function checkNamedDims(fileName: string, dims: Dims, where: string): void {
  if (dims.some((n) => !Number.isSafeInteger(n) || n < 1)) {
    throw new VolumeFileError(`${fileName}: the shape ${formatDims(dims)} ${where} is impossible: every dimension must be a whole number from 1 up`);
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
    throw new VolumeFileError(`${fileName}: the volume has no finite values (every decoded value is NaN or infinite): there is no surface to draw`);
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
      const facts: VolumeFileFacts = { ...base, kind: 'zfp-headerless', dtype: 'float32', dims: name.dims, rate: name.rate, missing: [], compresses: false };
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
            'the name must give the volume\'s shape and type (name_XxYxZ_dtype.raw)',
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
      throw new VolumeFileError(`${fileName}: this is an SWC neuron tracing, not a volume${reader === 'page' ? '; open it in the neuron example page' : ''}`);
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
      throw new VolumeFileError(`${fileName}: ${channels} samples per pixel (colour); an isosurface needs one value per voxel (save a single channel)`);
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
  if (rate === undefined || !Number.isFinite(rate) || rate <= 0) throw new VolumeFileError(`${fileName}: give a positive rate (bits per value), e.g. ${DEFAULT_RAW_RATE}`);
  return rate;
}

/**
 * Opens the file as a GPU stream, with `req` filling what `facts.missing`
 * lists (and choosing the rate of raw/NRRD volumes). Throws an error naming
 * the file; nothing stays allocated on failure.
 */
export async function openVolumeFile(device: GPUDevice, facts: VolumeFileFacts, bytes: Uint8Array, req: OpenRequest = {}, opts: OpenOptions = {}): Promise<OpenedVolume> {
  const { fileName } = facts;
  const display = fileName.split(/[\\/]/).pop() ?? fileName;
  const common = { name: display, fileName, kind: facts.kind, sourceBytes: facts.bytes, spacing: facts.spacing };
  if (req.dims) checkNamedDims(fileName, req.dims, 'given');
  switch (facts.kind) {
    case 'zfp':
    case 'zfp-headerless': {
      opts.onPhase?.('upload');
      let stream: ZfpGpuStream;
      const dims = req.dims ?? facts.dims;
      if (!dims) throw new VolumeFileError(`${fileName}: give the volume's dimensions (the name carries none)`);
      if (facts.kind === 'zfp-headerless' && (!facts.dims || req.dims)) {
        // The codec reads the shape from the name: hand it one that carries the given shape.
        const base = parseVolumeName(fileName).base || 'volume';
        const named = `${base}_${formatDims(dims)}_float32.zfp`;
        try {
          stream = loadZfpStream(device, bytes, named, { rate: req.rate ?? facts.rate });
        } catch (e) {
          if (e instanceof ZfpFormatError) throw new ZfpFormatError(e.message.split(named).join(fileName));
          throw e;
        }
      } else {
        stream = loadZfpStream(device, bytes, fileName, { rate: req.rate ?? facts.rate });
      }
      const info = stream.info;
      const notes = info.notes.map((n) => `${fileName}: ${n}`);
      return { ...common, stream, dims: info.dims, sourceDtype: 'float32', compressedBytes: info.paddedBytes, rate: info.rate, compressedHere: false, notes };
    }
    case 'raw':
    case 'nrrd':
    case 'tiff': {
      const dims = facts.kind === 'raw' ? (req.dims ?? facts.dims) : facts.dims;
      const dtype = facts.kind === 'raw' ? (req.dtype ?? facts.dtype) : facts.dtype;
      if (!dims || !dtype) throw new VolumeFileError(`${fileName}: give the volume's dimensions and sample type (the name carries none)`);
      let data = facts.kind === 'nrrd' ? facts.nrrd!.data : facts.kind === 'tiff' ? facts.samples! : bytes;
      if (sizeOf(dims, dtype) !== data.byteLength) {
        throw new VolumeFileError(`${fileName}: ${formatDims(dims)} ${dtype} is ${sizeOf(dims, dtype)} bytes, the file has ${data.byteLength}`);
      }
      const rate = checkRate(fileName, req.rate ?? DEFAULT_RAW_RATE);
      const notes: string[] = [];
      const nonFinite = countNonFinite(data, dtype);
      if (nonFinite && nonFiniteTotal(nonFinite) > 0) {
        if (nonFiniteTotal(nonFinite) === nonFinite.values) throw new VolumeFileError(`${fileName}: ${allNonFiniteMessage(nonFinite)}`);
        data = replaceNonFinite(data, dtype as 'float32' | 'float64', nonFinite);
        notes.push(`${fileName}: ${nonFiniteNotice(nonFinite)}`);
      }
      opts.onPhase?.('compress');
      const encoder = opts.encoder ?? (await encoderFor(device));
      let stream: ZfpGpuStream;
      try {
        stream = await encoder.compressToStream(data, dtype, dims, rate, { header: true, fileName });
      } catch (e) {
        // The shape or rate cannot be written as a zfp stream: the reader's error, naming the file.
        if (e instanceof ZfpFormatError) throw new VolumeFileError(e.message.includes(fileName) ? e.message : `${fileName}: ${e.message}`);
        throw e;
      }
      const nf = nonFinite && nonFiniteTotal(nonFinite) > 0 ? { nonFinite } : {};
      return { ...common, stream, dims, sourceDtype: dtype, compressedBytes: stream.info.paddedBytes, rate: stream.info.rate, compressedHere: true, notes, ...nf };
    }
  }
}

/** Compresses an uncompressed volume on the GPU (fixed rate, with header), with the device's shared encoder. */
export async function compressOnGpu(device: GPUDevice, data: Uint8Array, dtype: DType, dims: Dims, rate: number, fileName: string): Promise<ZfpGpuStream> {
  const encoder = await encoderFor(device);
  return encoder.compressToStream(data, dtype, dims, rate, { header: true, fileName });
}

export interface OpenBytesOptions extends OpenOptions, InspectOptions {
  /**
   * Raw, NRRD, TIFF: the rate to compress at (default DEFAULT_RAW_RATE).
   * Header-less zfp: the stream's rate when the name carries none.
   */
  rate?: number;
  /** Shape and sample type of a raw file whose name carries none. */
  dims?: Dims;
  dtype?: DType;
}

/** Why `facts` cannot be opened without asking, worded for `reader`. */
function missingMessage(facts: VolumeFileFacts, reader: VolumeReader): string {
  const { fileName } = facts;
  if (facts.kind === 'raw') {
    return `${fileName}: a raw volume needs its shape and type in the name (name_XxYxZ_dtype.raw)`;
  }
  if (facts.missing.includes('dims')) return `${fileName}: no zfp header and no shape in the name (name it name_XxYxZ_float32.raw.crateR.zfp)`;
  const fit = facts.fittingRates?.length ? ` (rates that fit its size: ${facts.fittingRates.join(', ')})` : '';
  return `${fileName}: no zfp header and no rate in the name (name_XxYxZ_float32.raw.crateR.zfp)${reader === 'command' ? '; give it with --rate R' : ''}${fit}`;
}

/**
 * Inspects and opens in one step, for callers that cannot ask (the CLI):
 * what the file does not say must be in `opts`, else a VolumeFileError says
 * what is missing. Header-less streams take the rate in their name first.
 */
export async function openVolumeBytes(device: GPUDevice, bytes: Uint8Array, fileName: string, opts: OpenBytesOptions = {}): Promise<OpenedVolume> {
  const reader = opts.reader ?? 'command';
  const facts = await inspectVolumeFile(fileName, bytes, { reader });
  const req: OpenRequest = {};
  if (facts.kind === 'zfp-headerless') req.rate = facts.rate ?? opts.rate;
  else if (facts.compresses) req.rate = opts.rate;
  if (facts.missing.includes('dims')) req.dims = opts.dims;
  if (facts.missing.includes('dtype')) req.dtype = opts.dtype;
  const unmet = facts.missing.filter((m) => req[m] === undefined);
  if (unmet.length > 0) throw new VolumeFileError(missingMessage(facts, reader));
  return openVolumeFile(device, facts, bytes, req, opts);
}

const KIND_LABEL: Record<VolumeFileKind, string> = { zfp: 'zfp file', 'zfp-headerless': 'header-less zfp file', raw: 'raw', nrrd: 'NRRD', tiff: 'TIFF stack' };

/** One line on what was opened and how, e.g. "uint8 raw 66x66x66 compressed on the GPU at rate 8" (CLI logs and JSON). */
export function describeOpenedVolume(v: OpenedVolume): string {
  if (v.kind === 'default') return `the built-in volume "${v.name}", ${formatDims(v.dims)} float32 compressed on the GPU at rate ${v.rate}`;
  if (!v.compressedHere) return `${KIND_LABEL[v.kind]} (${v.stream.info.mode}), used as is`;
  return `${KIND_LABEL[v.kind]} ${formatDims(v.dims)} ${v.sourceDtype} compressed on the GPU at rate ${v.rate}`;
}

/** The built-in volume (procedural.ts), compressed on the GPU at DEFAULT_VOLUME_RATE. */
export async function openDefaultVolume(device: GPUDevice, opts: OpenOptions & { rate?: number } = {}): Promise<OpenedVolume> {
  const volume = generateDefaultVolume();
  const rate = opts.rate ?? DEFAULT_VOLUME_RATE;
  opts.onPhase?.('compress');
  const encoder = opts.encoder ?? (await encoderFor(device));
  const bytes = new Uint8Array(volume.data.buffer, volume.data.byteOffset, volume.data.byteLength);
  const fileName = `${DEFAULT_VOLUME_NAME}_${formatDims(volume.dims)}_float32.raw`;
  const stream = await encoder.compressToStream(bytes, 'float32', volume.dims, rate, { header: true, fileName });
  return {
    stream,
    name: volume.name,
    fileName,
    kind: 'default',
    dims: volume.dims,
    sourceDtype: 'float32',
    sourceBytes: bytes.byteLength,
    compressedBytes: stream.info.paddedBytes,
    rate: stream.info.rate,
    compressedHere: true,
    defaultIsovalue: volume.defaultIsovalue,
    notes: [],
  };
}

/** True when `spec` names the built-in volume rather than a file (CLI). */
export function isDefaultVolume(spec: string): boolean {
  return spec === DEFAULT_VOLUME_NAME;
}
