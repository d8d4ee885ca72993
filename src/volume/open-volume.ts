// From a file's bytes (or the built-in default volume) to a fixed-rate zfp
// stream on the GPU: the one path the page, the CLI (extract, bench), the
// benchmarks and the tests share, so they compute the same surfaces for the
// same input.
//
//   zfp with header       -> validated and uploaded as is
//   header-less .zfp       -> shape and rate from the name (or given), uploaded
//   name_XxYxZ_dtype.raw   -> compressed on the GPU
//   .nrrd (raw or gzip)    -> compressed on the GPU
//   TIFF stack             -> read by libtiff (Wasm, src/loaders/tiff.ts), compressed likewise
//   "default"              -> generated (procedural.ts), compressed likewise
//
// Volumes compressed here take the rate chosen from their data (src/zfp/
// rate-choice.ts) unless one is given; either way the error is measured.
//
// inspectVolumeFile says what a file is and what is still missing (a raw
// file without shape, a header-less stream without rate) so a caller can ask
// for it; openVolumeFile does the work. openVolumeBytes does both for callers
// that cannot ask (the CLI: what is missing must come with the call).
// Errors name the file.
import { surfaceDimsProblem } from '../core/limits.ts';
import { ZfpFormatError } from '../zfp/header.ts';
import { loadZfpStream, type ZfpGpuStream } from '../zfp/gpu-stream.ts';
import { encoderFor, type ZfpEncoder } from '../zfp/encoder.ts';
import { chooseRate, type RateChoice } from '../zfp/rate-choice.ts';
import { errorMeterFor } from '../zfp/stream-error.ts';
import type { DType } from '../core/dtype.ts';
import { formatDims, parseVolumeName, type Dims } from '../core/naming.ts';
import {
  allNonFiniteMessage,
  countNonFinite,
  nonFiniteNotice,
  nonFiniteTotal,
  replaceNonFinite,
  type NonFiniteCount,
} from './non-finite.ts';
import { generateDefaultVolume } from './procedural.ts';
import {
  DEFAULT_VOLUME_NAME,
  type VolumeFileKind,
  VolumeFileError,
  type VolumeReader,
  type InspectOptions,
  type VolumeFileFacts,
  inspectVolumeFile,
  checkRate,
  checkNamedDims,
  sizeOf,
} from './inspect.ts';

// The inspection (what a file is) lives in inspect.ts; re-exported for the callers that open files.
export * from './inspect.ts';

export interface OpenRequest {
  dims?: Dims;
  dtype?: DType;
  /** Header-less zfp: the stream's rate. Raw/NRRD/TIFF: the rate to compress at (absent: chosen from the data, rate-choice.ts). */
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
  /** Where voxel (0, 0, 0) sits, in this volume's voxels (a store level's OME translation); 0 when absent. */
  origin?: [number, number, number];
  /** What the user should know about the file (non-finite values replaced, bytes ignored), one sentence each. */
  notes: string[];
  /** Float volumes compressed here: NaN/Inf counts (replaced before compression, see non-finite.ts). */
  nonFinite?: NonFiniteCount;
  /** Volumes compressed here: how the rate was found and the error it gives (sample and whole stream). */
  rateChoice?: RateChoice;
}

export interface OpenOptions {
  /** Reused between calls (pipelines compile once); created when absent. */
  encoder?: ZfpEncoder;
  onPhase?: (phase: OpenPhase) => void;
  /** Volumes compressed here: the largest stream (bytes) a rate chosen from the data may make. */
  maxStreamBytes?: number;
}

export { encoderFor } from '../zfp/encoder.ts';

/** Rates (multiples of 1/64) whose header-less stream of `dims` is exactly `bytes` long. */
/**
 * Opens the file as a GPU stream, with `req` filling what `facts.missing`
 * lists (and choosing the rate of raw/NRRD volumes). Throws an error naming
 * the file; nothing stays allocated on failure.
 */
export async function openVolumeFile(
  device: GPUDevice,
  facts: VolumeFileFacts,
  bytes: Uint8Array,
  req: OpenRequest = {},
  opts: OpenOptions = {},
): Promise<OpenedVolume> {
  const { fileName } = facts;
  const display = fileName.split(/[\\/]/).pop() ?? fileName;
  const common = { name: display, fileName, kind: facts.kind, sourceBytes: facts.bytes, spacing: facts.spacing };
  if (req.dims) checkNamedDims(fileName, req.dims, 'given');
  // refused before any upload, rate choice or compression (seconds for a big file)
  const known = req.dims ?? facts.dims;
  const tooWide = known ? surfaceDimsProblem(known) : null;
  if (tooWide) throw new VolumeFileError(`${fileName}: ${tooWide}`);
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
      return {
        ...common,
        stream,
        dims: info.dims,
        sourceDtype: 'float32',
        compressedBytes: info.paddedBytes,
        rate: info.rate,
        compressedHere: false,
        notes,
      };
    }
    case 'raw':
    case 'nrrd':
    case 'tiff': {
      const dims = facts.kind === 'raw' ? (req.dims ?? facts.dims) : facts.dims;
      const dtype = facts.kind === 'raw' ? (req.dtype ?? facts.dtype) : facts.dtype;
      if (!dims || !dtype) throw new VolumeFileError(`${fileName}: give the volume's dimensions and sample type (the name carries none)`);
      let data = facts.kind === 'nrrd' ? facts.nrrd!.data : facts.kind === 'tiff' ? facts.samples! : bytes;
      if (sizeOf(dims, dtype) !== data.byteLength) {
        throw new VolumeFileError(
          `${fileName}: ${formatDims(dims)} ${dtype} is ${sizeOf(dims, dtype)} bytes, the file has ${data.byteLength}`,
        );
      }
      if (req.rate !== undefined) checkRate(fileName, req.rate);
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
      let rateChoice: RateChoice;
      try {
        ({ stream, rateChoice } = await compressChosen(device, encoder, data, dtype, dims, fileName, req.rate, opts));
      } catch (e) {
        // The shape or rate cannot be written as a zfp stream: the reader's error, naming the file.
        if (e instanceof ZfpFormatError || e instanceof RangeError)
          throw new VolumeFileError(e.message.includes(fileName) ? e.message : `${fileName}: ${e.message}`);
        throw e;
      }
      if (rateChoice.warning) notes.push(rateChoice.warning);
      const nf = nonFinite && nonFiniteTotal(nonFinite) > 0 ? { nonFinite } : {};
      return {
        ...common,
        stream,
        dims,
        sourceDtype: dtype,
        compressedBytes: stream.info.paddedBytes,
        rate: stream.info.rate,
        compressedHere: true,
        notes,
        rateChoice,
        ...nf,
      };
    }
  }
}

/** The rate a volume held on the CPU would be compressed at, and why (no stream is kept): `cli info`. */
export async function chooseVolumeRate(
  device: GPUDevice,
  data: Uint8Array,
  dtype: DType,
  dims: Dims,
  opts: { rate?: number; maxStreamBytes?: number; fileName?: string } = {},
): Promise<RateChoice> {
  const encoder = await encoderFor(device);
  return chooseRate(encoder, await errorMeterFor(device), data, dtype, dims, opts);
}

/**
 * Chooses the rate (or measures the given one) on a sample, then compresses
 * the whole volume at it with its error measured on the way.
 */
async function compressChosen(
  device: GPUDevice,
  encoder: ZfpEncoder,
  data: Uint8Array,
  dtype: DType,
  dims: Dims,
  fileName: string,
  rate: number | undefined,
  opts: OpenOptions,
): Promise<{ stream: ZfpGpuStream; rateChoice: RateChoice }> {
  const meter = await errorMeterFor(device);
  const display = fileName.split(/[\\/]/).pop() ?? fileName;
  const rateChoice = await chooseRate(encoder, meter, data, dtype, dims, { rate, maxStreamBytes: opts.maxStreamBytes, fileName: display });
  const { stream, error } = await encoder.compressMeasured(data, dtype, dims, rateChoice.rate, meter, { header: true, fileName });
  rateChoice.stream = error;
  return { stream, rateChoice };
}

/** Compresses an uncompressed volume on the GPU (fixed rate, with header), with the device's shared encoder. */
export async function compressOnGpu(
  device: GPUDevice,
  data: Uint8Array,
  dtype: DType,
  dims: Dims,
  rate: number,
  fileName: string,
): Promise<ZfpGpuStream> {
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
  if (facts.missing.includes('dims'))
    return `${fileName}: no zfp header and no shape in the name (name it name_XxYxZ_float32.raw.crateR.zfp)`;
  const fit = facts.fittingRates?.length ? ` (rates that fit its size: ${facts.fittingRates.join(', ')})` : '';
  return `${fileName}: no zfp header and no rate in the name (name_XxYxZ_float32.raw.crateR.zfp)${reader === 'command' ? '; give it with --rate R' : ''}${fit}`;
}

/**
 * Inspects and opens in one step, for callers that cannot ask (the CLI):
 * what the file does not say must be in `opts`, else a VolumeFileError says
 * what is missing. Header-less streams take the rate in their name first.
 */
export async function openVolumeBytes(
  device: GPUDevice,
  bytes: Uint8Array,
  fileName: string,
  opts: OpenBytesOptions = {},
): Promise<OpenedVolume> {
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

const KIND_LABEL: Record<VolumeFileKind, string> = {
  zfp: 'zfp file',
  'zfp-headerless': 'header-less zfp file',
  raw: 'raw',
  nrrd: 'NRRD',
  tiff: 'TIFF stack',
};

/** One line on what was opened and how, e.g. "uint8 raw 66x66x66 compressed on the GPU at rate 8" (CLI logs and JSON). */
export function describeOpenedVolume(v: OpenedVolume): string {
  if (v.kind === 'default') return `the built-in volume "${v.name}", ${formatDims(v.dims)} float32 compressed on the GPU at rate ${v.rate}`;
  if (!v.compressedHere) return `${KIND_LABEL[v.kind]} (${v.stream.info.mode}), used as is`;
  return `${KIND_LABEL[v.kind]} ${formatDims(v.dims)} ${v.sourceDtype} compressed on the GPU at rate ${v.rate}`;
}

/** The built-in volume (procedural.ts), compressed on the GPU at the rate chosen from its data (or opts.rate). */
export async function openDefaultVolume(device: GPUDevice, opts: OpenOptions & { rate?: number } = {}): Promise<OpenedVolume> {
  const volume = generateDefaultVolume();
  opts.onPhase?.('compress');
  const encoder = opts.encoder ?? (await encoderFor(device));
  const bytes = new Uint8Array(volume.data.buffer, volume.data.byteOffset, volume.data.byteLength);
  const fileName = `${DEFAULT_VOLUME_NAME}_${formatDims(volume.dims)}_float32.raw`;
  const { stream, rateChoice } = await compressChosen(device, encoder, bytes, 'float32', volume.dims, fileName, opts.rate, opts);
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
    notes: rateChoice.warning ? [rateChoice.warning] : [],
    rateChoice,
  };
}

/** True when `spec` names the built-in volume rather than a file (CLI). */
export function isDefaultVolume(spec: string): boolean {
  return spec === DEFAULT_VOLUME_NAME;
}
