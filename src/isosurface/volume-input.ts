// A zfp stream on the GPU from the bytes of a volume file, for the CLI
// commands (extract, bench) and the benchmarks: zfp files (with header, or
// header-less with shape and rate from the name / a rate option) are
// uploaded as they are; uncompressed volumes (`name_XxYxZ_dtype.raw`, NRRD)
// are compressed on the GPU at a fixed rate first.
import { detectFile } from '../formats/detect.ts';
import { DTYPE_BYTES, type DType } from '../volume/dtype.ts';
import { formatDims, type Dims } from '../volume/naming.ts';
import { parseNrrd } from '../volume/nrrd.ts';
import { ZfpEncoder } from '../zfp/encoder.ts';
import { loadZfpStream, type ZfpGpuStream } from '../zfp/gpu-stream.ts';

export class VolumeInputError extends Error {
  constructor(message: string) {
    super(message);
    this.name = 'VolumeInputError';
  }
}

export interface VolumeInput {
  stream: ZfpGpuStream;
  /** What was done, e.g. "zfp file, fixed rate 4" or "uint8 raw compressed at rate 8". */
  how: string;
  /** The rate the data is compressed at. */
  rate: number;
}

export interface VolumeInputOptions {
  /** Rate for uncompressed input (default 8); for header-less zfp, the stream's rate when the name has none. */
  rate?: number;
  /** Shape and type of a raw file whose name carries none. */
  dims?: Dims;
  dtype?: DType;
}

/** Compresses an uncompressed volume on the GPU (fixed rate, with header). */
export async function compressOnGpu(device: GPUDevice, data: Uint8Array, dtype: DType, dims: Dims, rate: number, fileName: string): Promise<ZfpGpuStream> {
  const encoder = await ZfpEncoder.create(device, [dtype]);
  try {
    return await encoder.compressToStream(data, dtype, dims, rate, { header: true, fileName });
  } finally {
    encoder.destroy();
  }
}

export async function loadVolumeInput(device: GPUDevice, bytes: Uint8Array, fileName: string, opts: VolumeInputOptions = {}): Promise<VolumeInput> {
  const detected = detectFile(fileName, bytes.subarray(0, 16));
  if (detected.kind === 'zfp' || detected.kind === 'zfp-headerless') {
    const rate = detected.kind === 'zfp-headerless' ? (detected.name.rate ?? opts.rate) : undefined;
    const stream = loadZfpStream(device, bytes, fileName, rate === undefined ? {} : { rate });
    return { stream, how: `zfp file (${stream.info.mode}), used as is`, rate: stream.info.rate };
  }
  const rate = opts.rate ?? 8;
  if (detected.kind === 'nrrd') {
    const v = await parseNrrd(bytes);
    const stream = await compressOnGpu(device, v.data, v.dtype, v.dims, rate, fileName);
    return { stream, how: `NRRD ${formatDims(v.dims)} ${v.dtype} compressed on the GPU at rate ${rate}`, rate };
  }
  if (detected.kind === 'raw' || opts.dims) {
    const dims = opts.dims ?? detected.name.dims;
    const dtype = opts.dtype ?? detected.name.dtype;
    if (!dims || !dtype) throw new VolumeInputError(`${fileName}: a raw volume needs its shape and type in the name (name_XxYxZ_dtype.raw) or given`);
    const expect = dims[0] * dims[1] * dims[2] * DTYPE_BYTES[dtype];
    if (bytes.byteLength !== expect) throw new VolumeInputError(`${fileName}: ${formatDims(dims)} ${dtype} is ${expect} bytes, the file has ${bytes.byteLength}`);
    const stream = await compressOnGpu(device, bytes, dtype, dims, rate, fileName);
    return { stream, how: `raw ${formatDims(dims)} ${dtype} compressed on the GPU at rate ${rate}`, rate };
  }
  throw new VolumeInputError(`${fileName}: not a volume this command reads (${detected.why}); give a zfp file, a name_XxYxZ_dtype.raw volume or NRRD`);
}
