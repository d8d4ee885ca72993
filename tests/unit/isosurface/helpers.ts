// Shared by the isosurface tests: test volumes, compressing them on the GPU,
// decoding them back (what the surfaces must be computed from), and the
// decoded soup of the drawn surface.
import type { Dims } from '../../../src/core/naming.ts';
import type { Isosurface } from '../../../src/isosurface/isosurface.ts';
import { decodeVertices } from '../../../src/isosurface/vertex-format.ts';
import { ZfpDecoder } from '../../../src/zfp/decoder.ts';
import { ZfpEncoder } from '../../../src/zfp/encoder.ts';
import type { ZfpGpuStream } from '../../../src/zfp/gpu-stream.ts';
import { rng } from '../mc/reference.ts';
import { readVertices } from '../../helpers/isosurface-readback.ts';

/** Largest quantization error of a decoded vertex coordinate (half a step of 1/65535 along the edge), plus float32 slack. */
export const VERTEX_TOLERANCE = 0.5 / 65535 + 1e-4;

export type FieldKind = 'noise' | 'blobs';

/**
 * A test field: 'noise' (independent values: every case, many ambiguous ones)
 * or 'blobs' (a few Gaussian bumps: nested closed surfaces, like scans).
 */
export function makeField(dims: Dims, seed: number, kind: FieldKind): Float32Array {
  const [nx, ny, nz] = dims;
  const random = rng(seed);
  const out = new Float32Array(nx * ny * nz);
  if (kind === 'noise') {
    for (let i = 0; i < out.length; i++) out[i] = Math.fround(random() * 100);
    return out;
  }
  const blobs = Array.from({ length: 4 }, () => ({
    c: [random() * nx, random() * ny, random() * nz],
    r: 2 + random() * Math.max(nx, ny, nz) * 0.4,
    h: 50 + random() * 50,
  }));
  for (let z = 0; z < nz; z++) {
    for (let y = 0; y < ny; y++) {
      for (let x = 0; x < nx; x++) {
        let v = 0;
        for (const b of blobs) {
          const d2 = (x - b.c[0]) ** 2 + (y - b.c[1]) ** 2 + (z - b.c[2]) ** 2;
          v += b.h * Math.exp(-d2 / (b.r * b.r));
        }
        out[x + nx * (y + ny * z)] = Math.fround(v);
      }
    }
  }
  return out;
}

/** Compresses a float32 volume on the GPU (with zfp's header); the stream stays there. */
export async function compressVolume(
  device: GPUDevice,
  values: Float32Array,
  dims: Dims,
  rate: number,
  maxShardBytes?: number,
): Promise<ZfpGpuStream> {
  const encoder = await ZfpEncoder.create(device);
  try {
    return await encoder.compressToStream(new Uint8Array(values.buffer, values.byteOffset, values.byteLength), 'float32', dims, rate, {
      header: true,
      fileName: `test_${dims.join('x')}_float32.zfp`,
      maxShardBytes,
    });
  } finally {
    encoder.destroy();
  }
}

/**
 * The kernel families the surface tests force, so the VTK and cache tests run on both (unset: the
 * adapter's choice): ZFPISO_KERNEL_PATH=emulator|gpu forces the scans, the compactions and the zfp
 * decode (block list and whole volume); ZFPISO_DECODER_PATH=emulator|gpu forces the decode alone
 * and wins over it. Read through globalThis: the wgpu suite bundles these helpers for Deno.
 */
const testEnv = (globalThis as { process?: { env: Record<string, string | undefined> } }).process?.env ?? {};
export const testPrimitivePath = pathFromEnv('ZFPISO_KERNEL_PATH', testEnv.ZFPISO_KERNEL_PATH);
export const testDecoderPath = testEnv.ZFPISO_DECODER_PATH
  ? pathFromEnv('ZFPISO_DECODER_PATH', testEnv.ZFPISO_DECODER_PATH)
  : testPrimitivePath;
/** Isosurface options that apply the forced kernel families. */
export const testKernelOptions = { zfpDecoderPath: testDecoderPath, primitivePath: testPrimitivePath } as const;

function pathFromEnv(name: string, v: string | undefined): 'auto' | 'emulator' | 'gpu' {
  if (v === undefined || v === '' || v === 'auto') return 'auto';
  if (v === 'emulator' || v === 'gpu') return v;
  throw new Error(`${name} must be 'emulator', 'gpu' or 'auto' (got ${v})`);
}

/** The decoded volume of a stream (what every surface is computed from), on the forced decoder path. */
export async function decodeVolume(device: GPUDevice, stream: ZfpGpuStream): Promise<Float32Array> {
  const decoder = await ZfpDecoder.create(device, { path: testDecoderPath });
  try {
    return (await decoder.readVolume(stream))!;
  } finally {
    decoder.destroy();
  }
}

/** The drawn surface as a float32 soup in voxel index space. */
export async function drawnSoup(iso: Isosurface): Promise<Float32Array> {
  const packed = await readVertices(iso);
  return decodeVertices(packed, packed.length / 2, 2, iso.info.dims);
}
