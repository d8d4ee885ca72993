// The WebGPU measurements of the paper's comparison benchmarks, shared by
// the benchmark page (Chrome's WebGPU) and `npm run bench:paper` (Dawn in
// Node): whole-volume zfp decompression with our decoder, and the naive
// data-parallel marching cubes over the decompressed volume.
import { GpuTimer } from '../../gpu/timing.ts';
import { NaiveMarchingCubes, type NaiveMcResult } from '../../mc/naive-gpu.ts';
import type { Dims3 } from '../../mc/serial-mc.ts';
import type { ZfpDecoder } from '../../zfp/decoder.ts';
import type { ZfpGpuStream } from '../../zfp/gpu-stream.ts';

export interface GpuDecodeTimes {
  /** Per run: GPU time of the decode pass (timestamps) or submit-to-done wall time. */
  ms: number[];
  timing: 'timestamp-query' | 'queue-wall-time';
  floatBytes: number;
}

/** Decodes the whole stream `runs` times into one GPU buffer, one submission each. */
export async function timeGpuDecode(device: GPUDevice, decoder: ZfpDecoder, stream: ZfpGpuStream, runs: number): Promise<GpuDecodeTimes> {
  const [nx, ny, nz] = stream.info.dims;
  const output = device.createBuffer({
    label: 'paperBench.decoded',
    size: Math.max(4, nx * ny * nz * 4),
    usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC,
  });
  const timer = new GpuTimer(device, 4);
  try {
    const ms: number[] = [];
    for (let r = 0; r < runs; r++) {
      const frame = timer.begin();
      const encoder = device.createCommandEncoder({ label: 'paperBench.decode' });
      decoder.encodeDecodeVolume(encoder, { stream, output, timestampWrites: frame.pass('decode') });
      frame.resolve(encoder);
      device.queue.submit([encoder.finish()]);
      frame.submitted();
      ms.push((await frame.read()).totalMs);
    }
    return { ms, timing: timer.source, floatBytes: nx * ny * nz * 4 };
  } finally {
    timer.destroy();
    output.destroy();
  }
}

export interface NaiveMcTimes {
  results: NaiveMcResult[];
  /** GPU memory the naive method holds besides the volume, bytes (after the run). */
  workingBytes: number;
  volumeBytes: number;
}

/**
 * Naive marching cubes of the decompressed stream (decoded once on the GPU,
 * kept there) at each isovalue, one surface per submission, waiting for each.
 * `vertexCapacity` pre-sizes the soup (the largest surface, when known);
 * `cancelled` is asked before each surface (a time limit), ending the run early.
 */
export async function timeNaiveMc(
  device: GPUDevice,
  decoder: ZfpDecoder,
  stream: ZfpGpuStream,
  isovalues: number[],
  opts: {
    vertexCapacity?: number;
    onProgress?: (done: number, total: number, last: NaiveMcResult) => void;
    cancelled?: () => boolean;
  } = {},
): Promise<NaiveMcTimes> {
  const dims = stream.info.dims as Dims3;
  const volume = decoder.decodeVolume(stream);
  const mc = await NaiveMarchingCubes.create(device, { dims, initialVertexCapacity: opts.vertexCapacity });
  try {
    const results: NaiveMcResult[] = [];
    for (const iso of isovalues) {
      if (opts.cancelled?.()) break;
      const r = await mc.extract(volume, iso);
      results.push(r);
      opts.onProgress?.(results.length, isovalues.length, r);
    }
    return { results, workingBytes: mc.memoryBytes, volumeBytes: volume.size };
  } finally {
    mc.destroy();
    volume.destroy();
  }
}
