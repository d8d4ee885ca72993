// Full-volume zfp decompression (the paper's Table 3): each volume's decoded
// field compressed by zfpy at rates 2, 4 and 8 (fixed rate, with header),
// then decoded whole, `runs` + 1 times each (the first discarded), by our
// WebGPU decoder (GPU time of the decode pass), by zfp's serial C decoder
// through zfpy (native: zfp_decompress into a preallocated array, and
// decompress_numpy as users call it), and by zfp's C decoder compiled to
// WebAssembly, in Node and (by the caller) in Chromium. All decoders write
// into memory allocated before timing; all decodes are checked bit-identical.
import { execFileSync } from 'node:child_process';
import { createHash } from 'node:crypto';
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import type { GpuContext } from '../../src/gpu/device.ts';
import { timeGpuDecode } from '../../src/examples/paper-bench/gpu-measure.ts';
import { meanAfterFirst, timeZfpWasm } from '../../src/examples/paper-bench/measure.ts';
import type { ZfpDecoder } from '../../src/zfp/decoder.ts';
import { loadZfpStream } from '../../src/zfp/gpu-stream.ts';
import { decodeZfpWasm } from '../../src/loaders/zfp-wasm.ts';
import type { PreparedVolume } from './volumes.ts';

const ZFPY = `
import sys, json, time, hashlib, numpy as np, zfpy
raw, nx, ny, nz, out_prefix, runs = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), sys.argv[5], int(sys.argv[6])
rates = [float(r) for r in sys.argv[7].split(',')]
field = np.fromfile(raw, dtype=np.float32).reshape(nz, ny, nx)
answers = []
def timed(f):
    seconds = []
    for _ in range(runs):
        t = time.perf_counter(); f(); seconds.append(time.perf_counter() - t)
    return seconds
for rate in rates:
    data = zfpy.compress_numpy(field, rate=rate, write_header=True)
    path = '%s.rate%g.zfp' % (out_prefix, rate)
    open(path, 'wb').write(data)
    # zfp_decompress into a preallocated array (what our decoders do): the header-less
    # stream (the same bits after the header) through zfpy's _decompress(out=...).
    payload = zfpy.compress_numpy(field, rate=rate, write_header=False)
    out = np.empty_like(field)
    decoder_s = timed(lambda: zfpy._decompress(payload, zfpy.type_float, [nz, ny, nx], out=out, rate=rate))
    # As users call it: parse the header, allocate, decode.
    numpy_s = timed(lambda: zfpy.decompress_numpy(data))
    same = np.array_equal(zfpy.decompress_numpy(data).view(np.uint32), out.view(np.uint32))
    answers.append({'rate': rate, 'file': path, 'bytes': len(data), 'seconds': decoder_s, 'decompressNumpySeconds': numpy_s,
                    'sha256': hashlib.sha256(np.ascontiguousarray(out, dtype='<f4').tobytes()).hexdigest(), 'sameBothWays': bool(same)})
print(json.dumps({'numpy': np.__version__, 'rates': answers}))
`;

export interface ZfpRateResult {
  volume: string;
  rate: number;
  file: string;
  compressedBytes: number;
  floatBytes: number;
  /** ms per run, first included (it is discarded in the means). */
  webgpuMs: number[];
  webgpuTiming: string;
  /** Our decoder in Chromium's WebGPU (the same code, the browser's Dawn). */
  webgpuChromiumMs?: number[];
  /** zfp_decompress into a preallocated array (zfpy._decompress with out=). */
  zfpyMs: number[];
  /** zfpy.decompress_numpy (header, allocation, decode), as users call it. */
  zfpyDecompressNumpyMs: number[];
  wasmNodeMs: number[];
  wasmChromiumMs?: number[];
  wasmChromiumError?: string;
  /** zfpy, our WebGPU decoder and the Wasm decoder gave the same bits. */
  bitIdentical: boolean;
  mbps: {
    webgpu: number;
    webgpuChromium?: number;
    zfpySerial: number;
    zfpyDecompressNumpy: number;
    wasmNode: number;
    wasmChromium?: number;
  };
}

export function mbPerSecond(floatBytes: number, ms: number[]): number {
  return floatBytes / 1e6 / (meanAfterFirst(ms) / 1000);
}

const sha = (a: Float32Array) =>
  createHash('sha256')
    .update(new Uint8Array(a.buffer, a.byteOffset, a.byteLength))
    .digest('hex');

/** zfpy compresses and times; then our decoders run on zfpy's files. */
export async function runZfpVolume(
  root: string,
  gpu: GpuContext,
  decoder: ZfpDecoder,
  v: PreparedVolume,
  dataDir: string,
  rates: number[],
  runs: number,
): Promise<ZfpRateResult[]> {
  const python = join(root, '.venv', 'bin', 'python');
  const out = execFileSync(
    python,
    ['-c', ZFPY, v.rawPath, ...v.dims.map(String), join(dataDir, `${v.key}-zfp`), String(runs + 1), rates.join(',')],
    {
      encoding: 'utf8',
      maxBuffer: 1 << 26,
    },
  );
  const answer = JSON.parse(out) as {
    rates: {
      rate: number;
      file: string;
      bytes: number;
      seconds: number[];
      decompressNumpySeconds: number[];
      sha256: string;
      sameBothWays: boolean;
    }[];
  };
  const results: ZfpRateResult[] = [];
  for (const r of answer.rates) {
    const bytes = new Uint8Array(readFileSync(r.file));
    const stream = loadZfpStream(gpu.device, bytes, r.file.split('/').pop()!);
    try {
      const g = await timeGpuDecode(gpu.device, decoder, stream, runs + 1);
      const w = await timeZfpWasm(bytes, runs + 1, r.file);
      const gpuDecoded = (await decoder.readVolume(stream))!;
      const wasmDecoded = await decodeZfpWasm(bytes, r.file);
      const floatBytes = g.floatBytes;
      const zfpyMs = r.seconds.map((s) => s * 1000);
      results.push({
        volume: v.key,
        rate: r.rate,
        file: r.file.split('/').pop()!,
        compressedBytes: r.bytes,
        floatBytes,
        webgpuMs: g.ms,
        webgpuTiming: g.timing,
        zfpyMs,
        zfpyDecompressNumpyMs: r.decompressNumpySeconds.map((s) => s * 1000),
        wasmNodeMs: w.ms,
        bitIdentical: r.sameBothWays && sha(gpuDecoded) === r.sha256 && sha(wasmDecoded) === r.sha256,
        mbps: {
          webgpu: mbPerSecond(floatBytes, g.ms),
          zfpySerial: mbPerSecond(floatBytes, zfpyMs),
          zfpyDecompressNumpy: mbPerSecond(
            floatBytes,
            r.decompressNumpySeconds.map((s) => s * 1000),
          ),
          wasmNode: mbPerSecond(floatBytes, w.ms),
        },
      });
    } finally {
      stream.destroy();
    }
  }
  return results;
}
