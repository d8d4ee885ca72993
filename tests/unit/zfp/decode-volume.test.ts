// The whole-volume decode on both kernel families (emulator path:
// decode_volume.wgsl, GPU path: decode_volume_tiled.wgsl) against zfpy
// 1.0.1's decode and the CPU twin, bit for bit, on awkward shapes: single
// voxels, partial blocks on every face, block rows along x that are not a
// multiple of the GPU path's 32-block tile (34, 65 blocks), in one shard and
// in many small ones (shard boundaries inside block rows and tiles), in slabs
// of 2 block rows, with 2D dispatch grids; and on the shared volumes (bonsai,
// hydrogen atom). Block ranges (one kernel for both paths) against the CPU's
// ranges of zfpy's decode.
import { mkdtempSync, readFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { describe, expect } from 'vitest';
import { readF32 } from '../../../src/gpu/buffers.ts';
import { blockRanges, decodeVolume, toWords } from '../../../src/zfp/cpu/codec.ts';
import { ZfpDecoder } from '../../../src/zfp/decoder.ts';
import { openZfpStream } from '../../../src/zfp/format.ts';
import { loadZfpStream } from '../../../src/zfp/gpu-stream.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { runPython, sharedData } from '../../helpers/python.ts';
import { firstDifference } from './vectors.ts';

const PATHS = ['emulator', 'gpu'] as const;

type Dims3 = [number, number, number];

// x: 1 voxel, partial blocks, one block, 34 blocks (32 + 2), 65 blocks (2 tiles + 1)
const CASES: { dims: Dims3; rate: number }[] = [
  { dims: [1, 1, 1], rate: 8 },
  { dims: [3, 5, 7], rate: 5.5 },
  { dims: [4, 4, 4], rate: 3.25 },
  { dims: [5, 4, 4], rate: 12 },
  { dims: [63, 64, 65], rate: 4.75 },
  { dims: [133, 3, 9], rate: 7 },
  { dims: [257, 6, 2], rate: 2.5 },
];

// Random smooth fields with blocks of very different scales (zeros, subnormals, huge), compressed
// and decoded by zfpy with zfp's header; writes NAME.zfp and NAME.zfpy.raw.
const ZFPY_MAKE = `
import sys, json, numpy as np, zfpy
d, cases = sys.argv[1], json.loads(sys.argv[2])
rng = np.random.default_rng(17)
for i, c in enumerate(cases):
    x, y, z = c['dims']
    zz, yy, xx = np.meshgrid(np.arange(z), np.arange(y), np.arange(x), indexing='ij')
    a = (np.sin(0.3 * xx + 0.2 * yy) * np.cos(0.25 * zz) + 0.1 * rng.standard_normal((z, y, x)))
    scale = rng.choice([0.0, 1e-41, 3e37, 1.0, 1e-3, 1e5], size=(z, y, x))
    a = (a * scale).astype(np.float32)
    data = zfpy.compress_numpy(a, rate=c['rate'], write_header=True)
    open(f"{d}/case{i}.zfp", 'wb').write(data)
    np.ascontiguousarray(zfpy.decompress_numpy(data), dtype=np.float32).tofile(f"{d}/case{i}.zfpy.raw")
`;

function bytesOf(a: Float32Array): Uint8Array {
  return new Uint8Array(a.buffer, a.byteOffset, a.byteLength);
}

describe('ZfpDecoder whole-volume decode, both paths', () => {
  const dir = mkdtempSync(join(tmpdir(), 'zfp-volume-'));
  let made = false;
  const make = () => {
    if (!made) runPython(ZFPY_MAKE, [dir, JSON.stringify(CASES)]);
    made = true;
  };

  for (const path of PATHS) {
    gpuTest(`decodes awkward shapes bit for bit like zfpy and the CPU twin (${path} path)`, async ({ gpu }) => {
      const { device } = gpu;
      make();
      const decoder = await ZfpDecoder.create(device, { path });
      // 2D grids from 4 workgroups on: overshooting workgroups must write nothing
      const smallGrid = await ZfpDecoder.create(device, { path, maxWorkgroupsPerDimension: 3 });
      expect(decoder.path).toBe(path);
      for (const [i, c] of CASES.entries()) {
        const file = `case${i}_${c.dims.join('x')}.zfp`;
        const bytes = new Uint8Array(readFileSync(join(dir, `case${i}.zfp`)));
        const zfpy = new Uint8Array(readFileSync(join(dir, `case${i}.zfpy.raw`)));
        const info = openZfpStream(bytes, file);
        const cpu = decodeVolume(toWords(bytes), info.dims, info.bitsPerBlock, info.payloadBitOffset);
        expect(firstDifference(bytesOf(cpu), zfpy), `${file}: CPU twin vs zfpy`).toBe('identical');
        const ranges = blockRanges(new Float32Array(zfpy.buffer, zfpy.byteOffset, zfpy.byteLength / 4), c.dims);
        for (const [d, maxShardBytes] of [
          [decoder, undefined],
          [smallGrid, 700],
        ] as const) {
          const stream = loadZfpStream(device, bytes, file, { maxShardBytes });
          const what = `${file} (${path} path, ${stream.shards.length} shard(s))`;
          if (maxShardBytes && bytes.byteLength > 4 * maxShardBytes) expect(stream.shards.length, what).toBeGreaterThan(3);
          const slab = maxShardBytes ? c.dims[0] * c.dims[1] * 4 * 4 * 2 : undefined;
          const volume = (await d.readVolume(stream, { maxSlabBytes: slab }))!;
          expect(firstDifference(bytesOf(volume), zfpy), what).toBe('identical');
          const rangeBuffer = d.computeBlockRanges(stream);
          const got = await readF32(device, rangeBuffer);
          expect(firstDifference(bytesOf(got), bytesOf(ranges)), `ranges of ${what}`).toBe('identical');
          rangeBuffer.destroy();
          stream.destroy();
        }
      }
      decoder.destroy();
      smallGrid.destroy();
    });
  }

  gpuTest('decodes the shared volumes bit for bit like zfpy and the CPU twin (both paths)', async ({ gpu }) => {
    const { device } = gpu;
    const decoders = await Promise.all(PATHS.map((path) => ZfpDecoder.create(device, { path })));
    for (const name of ['hydrogen_atom_128x128x128_float32.rate8.zfp', 'bonsai_256x256x256_float32.rate4.zfp']) {
      const file = join(sharedData, 'volumes', name);
      const out = join(dir, `${name}.zfpy.raw`);
      runPython(
        `
import sys, numpy as np, zfpy
np.ascontiguousarray(zfpy.decompress_numpy(open(sys.argv[1], 'rb').read()), dtype=np.float32).tofile(sys.argv[2])
`,
        [file, out],
      );
      const zfpy = new Uint8Array(readFileSync(out));
      const bytes = new Uint8Array(readFileSync(file));
      const stream = loadZfpStream(device, bytes, name);
      const { info } = stream;
      const cpu = decodeVolume(toWords(bytes), info.dims, info.bitsPerBlock, info.payloadBitOffset);
      expect(firstDifference(bytesOf(cpu), zfpy), `${name}: CPU twin vs zfpy`).toBe('identical');
      for (const d of decoders) {
        const volume = (await d.readVolume(stream))!;
        expect(firstDifference(bytesOf(volume), zfpy), `${name} (${d.path} path)`).toBe('identical');
      }
      stream.destroy();
    }
    for (const d of decoders) d.destroy();
  });
});
