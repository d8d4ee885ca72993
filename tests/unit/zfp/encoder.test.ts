// The WGSL encoder against zfp 1.0.1: every vector input encodes to the
// vector's bytes (with and without header, in one shard and in several), and
// random volumes of odd sizes, every input type and random (fractional, and
// above 32: 148-bit header) rates encode to exactly the bytes of
// zfpy.compress_numpy(a.astype(np.float32), rate=R); zfpy decodes our files to
// exactly what our decoder gives, so the round trip has zfp's own error.
import { mkdtempSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { describe, expect } from 'vitest';
import { DTYPE_BYTES, type DType } from '../../../src/core/dtype.ts';
import type { Dims } from '../../../src/core/naming.ts';
import { ZfpDecoder } from '../../../src/zfp/decoder.ts';
import { ZfpEncoder } from '../../../src/zfp/encoder.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { runPython } from '../../helpers/python.ts';
import { firstDifference, readVector, rng, vectors } from './vectors.ts';

/** Random little-endian volume bytes of `dtype` with values that stress the coder. */
function randomVolume(dtype: DType, dims: Dims, random: () => number): Uint8Array {
  const n = dims[0] * dims[1] * dims[2];
  const bytes = new Uint8Array(n * DTYPE_BYTES[dtype]);
  const view = new DataView(bytes.buffer);
  const smooth = (i: number) => {
    const x = i % dims[0],
      y = Math.floor(i / dims[0]) % dims[1],
      z = Math.floor(i / (dims[0] * dims[1]));
    return Math.sin(0.3 * x + 0.2 * y) * Math.cos(0.25 * z) + 0.1 * (random() - 0.5);
  };
  // the scale changes every 64 voxels, so blocks see very different exponents
  // zeros, subnormals, values below 2^-97 (zfp's scale factor overflows), near FLT_MAX, ordinary
  const scales = [0, 1e-41, 1e-33, 3e37, 1];
  const offset = Math.floor(random() * scales.length);
  let scale = 1;
  for (let i = 0; i < n; i++) {
    if (i % 64 === 0) {
      scale = scales[(i / 64 + offset) % scales.length];
      if (scale === 1) scale = 10 ** (12 * random() - 6);
    }
    switch (dtype) {
      case 'uint8':
        view.setUint8(i, Math.floor(random() * 256));
        break;
      case 'int8':
        view.setInt8(i, Math.floor(random() * 256) - 128);
        break;
      case 'uint16':
        view.setUint16(i, Math.floor(random() * 65536), true);
        break;
      case 'int16':
        view.setInt16(i, Math.floor(random() * 65536) - 32768, true);
        break;
      case 'float32': {
        const v = scale === 0 && random() < 0.5 ? -0 : smooth(i) * scale;
        view.setFloat32(i * 4, v, true);
        break;
      }
      case 'float64': {
        const r = random();
        // ties of the float32 rounding, values that round to float32 subnormals, and plain doubles
        const v = r < 0.1 ? (1 + 2 ** -24) * 2 ** Math.floor(40 * random() - 20) : r < 0.15 ? 3 * 2 ** -151 : smooth(i) * scale;
        view.setFloat64(i * 8, v, true);
        break;
      }
    }
  }
  return bytes;
}

describe('ZfpEncoder', () => {
  gpuTest('encodes every vector input to the vector bit for bit (header or not, one shard or several)', async ({ gpu }) => {
    const encoder = await ZfpEncoder.create(gpu.device);
    for (const v of vectors) {
      const input = readVector(v.input);
      for (const [file, header] of [
        [v.compressed, false],
        [v.with_header.file, true],
      ] as const) {
        for (const maxShardBytes of [undefined, 80000]) {
          const stream = await encoder.compressToStream(input, 'float32', v.dims_xyz, v.rate, { header, maxShardBytes });
          if (maxShardBytes) expect(stream.shards.length).toBeGreaterThan(1);
          const bytes = await stream.readBytes();
          expect(firstDifference(bytes, readVector(file)), `${file}, ${stream.shards.length} shard(s)`).toBe('identical');
          stream.destroy();
        }
      }
    }
    encoder.destroy();
  });

  gpuTest('random volumes of odd sizes, every input type, random rates: zfpy bytes, zfpy decode = ours', async ({ gpu }) => {
    const { device } = gpu;
    const encoder = await ZfpEncoder.create(device);
    const decoder = await ZfpDecoder.create(device);
    const random = rng(2024);
    const dir = mkdtempSync(join(tmpdir(), 'zfp-roundtrip-'));
    const dtypes: DType[] = ['uint8', 'float32', 'int8', 'float64', 'uint16', 'float32', 'int16', 'float64'];
    const fixedRates = [0.1328125, 1, 2.5, 7.3, 33];
    const cases: { name: string; dims: Dims; dtype: DType; rate: number; header: boolean }[] = [];
    for (let i = 0; i < 32; i++) {
      const odd = () => 1 + 2 * Math.floor(random() * 12); // 1, 3, ..., 23
      const dims: Dims = [odd(), odd(), odd()];
      if (i % 4 === 1) dims[i % 3] = 2 + Math.floor(random() * 3); // 2..4 along one axis
      const rate = i < fixedRates.length ? fixedRates[i] : Math.round((0.14 + random() * 24) * 1000) / 1000;
      cases.push({ name: `case${i}`, dims, dtype: dtypes[i % dtypes.length], rate, header: i % 3 !== 2 });
    }
    for (const c of cases) {
      const volume = randomVolume(c.dtype, c.dims, random);
      writeFileSync(join(dir, `${c.name}.in`), volume);
      // small shards for some cases: several z rows of blocks, each with its own input slab
      const maxShardBytes = c.dims[2] > 8 && c.name.endsWith('3') ? c.dims[0] * c.dims[1] * 4 * DTYPE_BYTES[c.dtype] * 2 + 4096 : undefined;
      const stream = await encoder.compressToStream(volume, c.dtype, c.dims, c.rate, { header: c.header, maxShardBytes });
      writeFileSync(join(dir, `${c.name}.zfp`), await stream.readBytes());
      writeFileSync(join(dir, `${c.name}.ours.raw`), (await decoder.readVolume(stream))!);
      stream.destroy();
    }
    const out = runPython(
      `
import sys, json, numpy as np, zfpy
d, cases = sys.argv[1], json.loads(sys.argv[2])
res = []
for c in cases:
    x, y, z = c['dims']
    a = np.fromfile(d + '/' + c['name'] + '.in', dtype=np.dtype(c['dtype']).newbyteorder('<')).reshape(z, y, x)
    f = a.astype(np.float32)
    ref = zfpy.compress_numpy(f, rate=c['rate'], write_header=c['header'])
    ours = open(d + '/' + c['name'] + '.zfp', 'rb').read()
    if c['header']:
        dec = zfpy.decompress_numpy(ours)
    else:
        dec = zfpy._decompress(ours, zfpy.type_float, [z, y, x], rate=c['rate'])
    dec = np.ascontiguousarray(dec, dtype=np.float32)
    mine = np.fromfile(d + '/' + c['name'] + '.ours.raw', dtype='<f4').reshape(z, y, x)
    own = zfpy.decompress_numpy(zfpy.compress_numpy(f, rate=c['rate'], write_header=True))
    finite = np.isfinite(f)
    res.append({
        'same_bytes': ref == ours,
        'sizes': [len(ref), len(ours)],
        'zfpy_decodes_ours_as_we_do': bool(np.array_equal(dec.view(np.uint32), mine.view(np.uint32))),
        'error_ours': float(np.max(np.abs(mine[finite].astype(np.float64) - f[finite]))) if finite.any() else 0.0,
        'error_zfp': float(np.max(np.abs(own[finite].astype(np.float64) - f[finite]))) if finite.any() else 0.0,
    })
print(json.dumps(res))
`,
      [dir, JSON.stringify(cases)],
    );
    const results = JSON.parse(out) as {
      same_bytes: boolean;
      sizes: number[];
      zfpy_decodes_ours_as_we_do: boolean;
      error_ours: number;
      error_zfp: number;
    }[];
    results.forEach((r, i) => {
      const what = JSON.stringify(cases[i]);
      expect(r.same_bytes, `${what}: bytes equal to zfpy's (sizes ${r.sizes})`).toBe(true);
      expect(r.zfpy_decodes_ours_as_we_do, `${what}: zfpy decodes our file as our decoder does`).toBe(true);
      expect(r.error_ours, `${what}: max error`).toBe(r.error_zfp);
    });
    encoder.destroy();
    decoder.destroy();
  });

  gpuTest('rejects a volume whose size does not match, before allocating', async ({ gpu }) => {
    const encoder = await ZfpEncoder.create(gpu.device);
    await expect(encoder.compressToStream(new Uint8Array(100), 'uint8', [5, 5, 5], 4)).rejects.toThrow(/5x5x5 uint8 is 125 bytes, got 100/);
    await expect(encoder.compressToStream(new Uint8Array(125), 'uint8', [5, 5, 5], 0.05)).rejects.toThrow(
      /fewer than the 9 a float32 block needs/,
    );
    encoder.destroy();
  });
});
