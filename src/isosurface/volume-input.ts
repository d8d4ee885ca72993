// Opening volume files lives in one module, src/volume/open-volume.ts (the
// page, the CLI, the benchmarks). These two names remain for the benchmark
// code that imports them from here (benchmarks/isosurface.ts,
// benchmarks/paper/, the paper-bench page); new code imports
// openVolumeBytes / compressOnGpu from open-volume.ts.
import type { DType } from '../volume/dtype.ts';
import type { Dims } from '../volume/naming.ts';
import { describeOpenedVolume, openVolumeBytes } from '../volume/open-volume.ts';
import type { ZfpGpuStream } from '../zfp/gpu-stream.ts';

export { compressOnGpu } from '../volume/open-volume.ts';

export interface VolumeInput {
  stream: ZfpGpuStream;
  /** What was done, e.g. "zfp file (fixed rate 4 …), used as is" or "raw 66x66x66 uint8 compressed on the GPU at rate 8". */
  how: string;
  /** The rate the data is compressed at. */
  rate: number;
}

/** openVolumeBytes (worded for a command), as {stream, how, rate}. */
export async function loadVolumeInput(device: GPUDevice, bytes: Uint8Array, fileName: string, opts: { rate?: number; dims?: Dims; dtype?: DType } = {}): Promise<VolumeInput> {
  const v = await openVolumeBytes(device, bytes, fileName, { ...opts, reader: 'command' });
  return { stream: v.stream, how: describeOpenedVolume(v), rate: v.rate };
}
