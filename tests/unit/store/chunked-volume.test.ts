// A level of a chunked store streamed into the isosurface pipeline through a
// GPU chunk pool (src/zfp/chunked-volume.ts). Stores are written by our
// converter (numcodecs zfpy, fixed rate); the reference is the in-core
// pipeline on the same volume compressed as ONE stream by zfpy at the same
// rate (zfp codes every 4^3 block alone, so the blocks are the same): the
// surfaces must be identical, vertex for vertex. Also: only the chunks whose
// 27-chunk neighbourhood range (from the store's ranges array) contains the
// isovalue give the same surface; slots reused after evictions serve no stale
// blocks; bad chunks and a full pool are refused with the chunk named.
import { execFileSync } from 'node:child_process';
import { existsSync, mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect } from 'vitest';
import { Isosurface } from '../../../src/isosurface/isosurface.ts';
import { ChunkedVolume, ChunkError, type ChunkLevelLayout } from '../../../src/zfp/chunked-volume.ts';

import { bitsPerBlockForRate, fixedRateStreamBytes, planZfpStream } from '../../../src/zfp/format.ts';
import { decodeVolume as cpuDecodeVolume, encodeVolume as cpuEncodeVolume } from '../../../src/zfp/cpu/codec.ts';
import { writeZfpHeader } from '../../../src/zfp/header.ts';
import { decodeVertices } from '../../../src/isosurface/vertex-format.ts';
import { marchingCubes } from '../../../src/mc/serial-mc.ts';
import { loadZfpStream } from '../../../src/zfp/gpu-stream.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { readVertices } from '../../helpers/isosurface-readback.ts';
import { repoRoot, sharedData } from '../../helpers/python.ts';

const work = mkdtempSync(join(tmpdir(), 'chunked-volume-'));
afterAll(() => rmSync(work, { recursive: true, force: true }));

interface Case {
  key: string;
  input: string;
  dims: [number, number, number];
  chunk: number;
  rate: number;
  isovalues: number[];
  /** Also check the surface from just the needed chunks. */
  partial: boolean;
}

const cases: Case[] = [
  // 66^3 in 32^3 chunks: partial chunks and partial blocks at the far edges
  {
    key: 'neghip',
    input: 'volumes/neghip_66x66x66_uint8.raw',
    dims: [66, 66, 66],
    chunk: 32,
    rate: 4,
    isovalues: [40.37, 133.37],
    partial: true,
  },
  {
    key: 'hydrogen',
    input: 'volumes/hydrogen_atom_128x128x128_float32.raw',
    dims: [128, 128, 128],
    chunk: 32,
    rate: 6,
    isovalues: [9.37, 60.37],
    partial: true,
  },
  // 64^3 chunks (the converter's default): groups of 16^3 blocks
  {
    key: 'bonsai',
    input: 'volumes/bonsai_256x256x256_float32.rate4.zfp',
    dims: [256, 256, 256],
    chunk: 64,
    rate: 4,
    isovalues: [80.37],
    partial: false,
  },
];

interface Made {
  store: string;
  /** The whole volume as one zfp stream (zfpy, same rate, header). */
  whole: Uint8Array;
  /** [cz][cy][cx] -> [min, max] of the store's ranges/0 (decoded values). */
  ranges: Float32Array;
  layout: ChunkLevelLayout;
}

const made = new Map<string, Made>();

beforeAll(() => {
  for (const c of cases) {
    const store = join(work, `${c.key}.zarr`);
    execFileSync(
      process.execPath,
      [
        join(repoRoot, 'scripts/convert.mjs'),
        join(sharedData, c.input),
        '--out',
        store,
        '--chunk',
        String(c.chunk),
        '--rate',
        String(c.rate),
        '--levels',
        '1',
        '--quiet',
      ],
      {
        cwd: repoRoot,
        stdio: 'pipe',
        timeout: 900_000,
      },
    );
    const python = join(repoRoot, '.venv-converter/bin/python');
    // zfpy's one-stream compression of the level-0 values, and the store's per-chunk ranges
    execFileSync(
      python,
      [
        '-c',
        `
import sys, numpy as np, zarr, zfpy
store, raw, dtype, nx, ny, nz, rate, out = sys.argv[1:]
if raw.endswith('.zfp'):
    a = zfpy.decompress_numpy(open(raw, 'rb').read()).astype(np.float32)
else:
    a = np.fromfile(raw, dtype=dtype).reshape(int(nz), int(ny), int(nx)).astype(np.float32)
open(out + '.zfp', 'wb').write(zfpy.compress_numpy(a, rate=float(rate), write_header=True))
g = zarr.open_group(store, mode='r')
np.asarray(g['ranges/0'][...], dtype='<f4').tofile(out + '.ranges')
`,
        store,
        join(sharedData, c.input),
        c.input.includes('uint8') ? 'uint8' : '<f4',
        ...c.dims.map(String),
        String(c.rate),
        join(work, c.key),
      ],
      { encoding: 'utf8' },
    );
    const grid = c.dims.map((n) => Math.ceil(n / c.chunk)) as [number, number, number];
    const first = readFileSync(join(store, '0', 'c', '0', '0', '0'));
    made.set(c.key, {
      store,
      whole: new Uint8Array(readFileSync(join(work, `${c.key}.zfp`))),
      ranges: new Float32Array(new Uint8Array(readFileSync(join(work, `${c.key}.ranges`))).buffer),
      layout: {
        dims: c.dims,
        chunkEdge: c.chunk,
        chunkGrid: grid,
        rate: c.rate,
        chunkBytes: first.byteLength,
        name: `${c.key}.zarr level 0`,
      },
    });
  }
}, 900_000);

function chunkBytes(m: Made, chunk: number): Uint8Array {
  const [gx, gy] = m.layout.chunkGrid;
  const x = chunk % gx;
  const y = Math.floor(chunk / gx) % gy;
  const z = Math.floor(chunk / (gx * gy));
  const file = join(m.store, '0', 'c', String(z), String(y), String(x));
  if (!existsSync(file)) throw new Error(`missing chunk file ${file}`);
  return new Uint8Array(readFileSync(file));
}

/** Chunks whose range united with their 26 neighbours' holds iso (lo < iso <= hi, the pipeline's rule). */
function neededChunks(m: Made, iso: number): number[] {
  const [gx, gy, gz] = m.layout.chunkGrid;
  const out: number[] = [];
  for (let z = 0; z < gz; z++)
    for (let y = 0; y < gy; y++)
      for (let x = 0; x < gx; x++) {
        let lo = Infinity;
        let hi = -Infinity;
        for (let dz = -1; dz <= 1; dz++)
          for (let dy = -1; dy <= 1; dy++)
            for (let dx = -1; dx <= 1; dx++) {
              const [u, v, w] = [x + dx, y + dy, z + dz];
              if (u < 0 || v < 0 || w < 0 || u >= gx || v >= gy || w >= gz) continue;
              const at = 2 * (u + gx * (v + gy * w));
              lo = Math.min(lo, m.ranges[at]);
              hi = Math.max(hi, m.ranges[at + 1]);
            }
        if (lo < iso && iso <= hi) out.push(x + gx * (y + gy * z));
      }
  return out;
}

const allChunks = (m: Made) => Array.from({ length: m.layout.chunkGrid.reduce((a, b) => a * b, 1) }, (_, i) => i);

describe('a chunked store level through the GPU chunk pool', () => {
  for (const c of cases) {
    gpuTest(
      `${c.key}: every chunk resident = the in-core pipeline on one zfpy stream, vertex for vertex; the needed chunks alone give the same`,
      async ({ gpu }) => {
        const m = made.get(c.key)!;
        const stream = loadZfpStream(gpu.device, m.whole, `${c.key}.zfp`);
        const groupEdgeBlocks = c.chunk / 4;
        const inCore = await Isosurface.create(gpu, stream, { groupEdgeBlocks });
        const pool = ChunkedVolume.create(gpu, m.layout, { poolChunks: allChunks(m).length });
        for (const chunk of allChunks(m)) pool.put(chunk, chunkBytes(m, chunk));
        expect(pool.residentCount).toBe(allChunks(m).length);
        const chunked = await Isosurface.create(gpu, pool);
        // per-block state follows the pool (its slots x blocks per chunk), not the level
        expect(chunked.info.blockCount).toBe(pool.poolChunks * pool.blocksPerChunk);
        for (const iso of c.isovalues) {
          const a = await inCore.compute(iso);
          const b = await chunked.compute(iso);
          expect(a.triangles, `iso ${iso}`).toBeGreaterThan(100);
          expect(b.triangles, `iso ${iso}`).toBe(a.triangles);
          expect(b.activeBlocks, `iso ${iso}`).toBe(a.activeBlocks);
          const [va, vb] = await Promise.all([readVertices(inCore), readVertices(chunked)]);
          expect(vb.length).toBe(va.length);
          expect(Buffer.from(vb.buffer).equals(Buffer.from(va.buffer)), `iso ${iso}: vertices`).toBe(true);
        }
        // A second surface over the same pool (the stream controller makes one each time a level is shown again): it starts from every resident chunk.
        chunked.destroy();
        const again = await Isosurface.create(gpu, pool);
        expect((await again.compute(c.isovalues[0])).triangles).toBe((await inCore.compute(c.isovalues[0])).triangles);
        again.destroy();
        pool.destroy();

        // Only the chunks the surface needs: the same surface from fewer chunks.
        for (const iso of c.partial ? c.isovalues : []) {
          const need = neededChunks(m, iso);
          expect(need.length).toBeLessThanOrEqual(allChunks(m).length);
          const partial = ChunkedVolume.create(gpu, m.layout, { poolChunks: need.length });
          for (const chunk of need) partial.put(chunk, chunkBytes(m, chunk));
          const iso2 = await Isosurface.create(gpu, partial);
          const a = await inCore.compute(iso);
          const b = await iso2.compute(iso);
          expect(b.triangles, `iso ${iso} from ${need.length} chunks`).toBe(a.triangles);
          const [va, vb] = await Promise.all([readVertices(inCore), readVertices(iso2)]);
          expect(Buffer.from(vb.buffer).equals(Buffer.from(va.buffer)), `iso ${iso}: vertices from the needed chunks`).toBe(true);
          iso2.destroy();
          partial.destroy();
        }
        inCore.destroy();
        stream.destroy();
      },
      600_000,
    );
  }

  gpuTest(
    'hydrogen: a narrow surface needs a fraction of the chunks; evicted slots are reused without stale blocks',
    async ({ gpu }) => {
      const m = made.get('hydrogen')!;
      // the narrowest of a few surfaces (it must need under half of the store) and a wide one
      const candidates = [30.37, 60.37, 120.37, 180.37, 230.37]
        .map((iso) => ({ iso, need: neededChunks(m, iso) }))
        .filter((x) => x.need.length > 0);
      const narrow = candidates.reduce((a, b) => (b.need.length < a.need.length ? b : a));
      const [high, low] = [narrow.iso, 9.37];
      const needHigh = narrow.need;
      const needLow = neededChunks(m, low);
      expect(needHigh.length).toBeLessThan(allChunks(m).length / 2);
      expect(needLow.length).toBeGreaterThan(needHigh.length);
      const stream = loadZfpStream(gpu.device, m.whole, 'hydrogen.zfp');
      const inCore = await Isosurface.create(gpu, stream, { groupEdgeBlocks: 8 });
      const expected = new Map<number, number>();
      for (const iso of [high, low]) expected.set(iso, (await inCore.compute(iso)).triangles);
      expect(expected.get(high)).toBeGreaterThan(0);
      // A pool just large enough for the larger set, so the second set reuses freed slots.
      const pool = ChunkedVolume.create(gpu, m.layout, { poolChunks: Math.max(needHigh.length, needLow.length) });
      const surface = await Isosurface.create(gpu, pool);
      for (const chunk of needHigh) pool.put(chunk, chunkBytes(m, chunk));
      expect((await surface.compute(high)).triangles).toBe(expected.get(high));
      for (const chunk of needHigh) pool.evict(chunk);
      expect(pool.residentCount).toBe(0);
      // nothing resident: no surface, whatever the block cache still holds
      expect((await surface.compute(high)).triangles).toBe(0);
      for (const chunk of needLow) pool.put(chunk, chunkBytes(m, chunk));
      expect((await surface.compute(low)).triangles).toBe(expected.get(low));
      surface.destroy();
      pool.destroy();
      inCore.destroy();
      stream.destroy();
    },
    600_000,
  );

  gpuTest("chunks that are not this level's and a full pool are refused, naming the chunk; the pool stays usable", async ({ gpu }) => {
    const m = made.get('neghip')!;
    const pool = ChunkedVolume.create(gpu, m.layout, { poolChunks: 2 });
    const good = chunkBytes(m, 0);
    expect(() => pool.put(1, good.subarray(0, good.length - 8))).toThrow(
      /neghip\.zarr level 0 chunk \(1, 0, 0\): \d+ bytes, but a 32\^3 chunk at rate 4 is \d+ bytes/,
    );
    const other = made.get('hydrogen')!;
    expect(() => pool.put(1, chunkBytes(other, 0).subarray(0, good.length))).toThrow(ChunkError);
    const lying = good.slice();
    lying[0] = 0x41; // not the zfp magic
    expect(() => pool.put(2, lying)).toThrow(/neghip\.zarr level 0 chunk \(2, 0, 0\)/);
    expect(() => pool.put(999, good)).toThrow(/there is no chunk 999/);
    // other bytes under an index put before (the store changed while open): refused, even after an eviction
    pool.put(3, chunkBytes(m, 3));
    pool.evict(3);
    expect(() => pool.put(3, chunkBytes(m, 4))).toThrow(/chunk \(0, 1, 0\): its bytes differ from those read before/);
    pool.put(3, chunkBytes(m, 3));
    pool.evict(3);
    pool.put(0, good);
    pool.put(1, chunkBytes(m, 1));
    expect(() => pool.put(2, chunkBytes(m, 2))).toThrow(/chunk \(2, 0, 0\): the pool is full \(2 chunks\)/);
    expect(pool.residentCount).toBe(2);
    expect(() => ChunkedVolume.create(gpu, { ...m.layout, chunkEdge: 30 }, { poolChunks: 1 })).toThrow(
      /chunk edge 30 is not a multiple of 4/,
    );
    expect(() => ChunkedVolume.create(gpu, { ...m.layout, chunkBytes: 100 }, { poolChunks: 1 })).toThrow(
      /is \d+ bytes as zfp writes it, not 100/,
    );
    // a hostile size from store metadata: refused before the page table is allocated
    const tiny = planZfpStream('4^3 chunk', [4, 4, 4], 4, true).paddedBytes;
    const huge: ChunkLevelLayout = {
      ...m.layout,
      dims: [2 ** 12, 2 ** 12, 2 ** 13],
      chunkEdge: 4,
      chunkGrid: [2 ** 10, 2 ** 10, 2 ** 11],
      chunkBytes: tiny,
    };
    expect(() => ChunkedVolume.create(gpu, huge, { poolChunks: 1 })).toThrow(
      /chunks need \d+ bytes of tables \(chunk -> slot, slot -> chunk\), more than one storage binding/,
    );
    pool.destroy();
  });

  gpuTest(
    'a level past 32-bit bit offsets (16384 x 128 x 128 at rate 16: 2^32 bits), chunks only at the far corner: the serial MC surface, placed there',
    async ({ gpu }) => {
      // Made on the CPU (our zfp twin), so this runs where Python does not (the wgpu suite).
      const C = 64;
      const rate = 16;
      const dims: [number, number, number] = [16384, 128, 128];
      const chunkGrid: [number, number, number] = [256, 2, 2];
      const bits = bitsPerBlockForRate(rate);
      expect((dims[0] / 4) * (dims[1] / 4) * (dims[2] / 4) * bits).toBeGreaterThanOrEqual(2 ** 32);
      const header = writeZfpHeader([C, C, C], bits);
      const chunkBytesOf = fixedRateStreamBytes((C / 4) ** 3, bits, header.bits);
      const layout: ChunkLevelLayout = { dims, chunkEdge: C, chunkGrid, rate, chunkBytes: chunkBytesOf, name: 'far.zarr level 0' };
      // a ball at the far end of x: max(0, 40 - distance to (16320, 64, 64)), in the chunks x = 254, 255
      const x0 = 16384 - 2 * C;
      const region = new Float32Array(2 * C * 128 * 128);
      const decoded = new Float32Array(region.length);
      const pool = ChunkedVolume.create(gpu, layout, { poolChunks: 8 });
      const chunk = new Float32Array(C * C * C);
      for (let cz = 0; cz < 2; cz++)
        for (let cy = 0; cy < 2; cy++)
          for (let cx = 254; cx < 256; cx++) {
            for (let z = 0; z < C; z++)
              for (let y = 0; y < C; y++)
                for (let x = 0; x < C; x++) {
                  const d = Math.hypot(cx * C + x - 16320, cy * C + y - 64, cz * C + z - 64);
                  chunk[x + C * (y + C * z)] = Math.max(0, 40 - d);
                }
            const bytes = new Uint8Array(chunkBytesOf);
            bytes.set(header.bytes);
            const words = new Uint32Array(bytes.buffer);
            cpuEncodeVolume(chunk, [C, C, C], bits, words, header.bits);
            pool.put(cx + 256 * (cy + 2 * cz), bytes);
            const back = cpuDecodeVolume(words, [C, C, C], bits, header.bits);
            for (let z = 0; z < C; z++)
              for (let y = 0; y < C; y++)
                for (let x = 0; x < C; x++)
                  decoded[cx * C - x0 + x + 2 * C * (cy * C + y + 128 * (cz * C + z))] = back[x + C * (y + C * z)];
          }
      const iso = 10.37;
      const surface = await Isosurface.create(gpu, pool);
      const stats = await surface.compute(iso);
      const reference = marchingCubes(decoded, [2 * C, 128, 128], iso);
      expect(stats.triangles).toBeGreaterThan(1000);
      expect(stats.triangles).toBe(reference.triangleCount);
      const mesh = await surface.readMesh();
      const p = decodeVertices(mesh.vertices, mesh.vertices.length / 3);
      let minX = Infinity;
      let maxX = -Infinity;
      for (let i = 0; i < p.length; i += 3) {
        minX = Math.min(minX, p[i]);
        maxX = Math.max(maxX, p[i]);
      }
      let refMin = Infinity;
      let refMax = -Infinity;
      for (let i = 0; i < reference.positions.length; i += 3) {
        refMin = Math.min(refMin, reference.positions[i] + x0);
        refMax = Math.max(refMax, reference.positions[i] + x0);
      }
      // placed at the far corner: block coordinates near 4095 along x
      expect(Math.abs(minX - refMin)).toBeLessThan(0.01);
      expect(Math.abs(maxX - refMax)).toBeLessThan(0.01);
      surface.destroy();
      pool.destroy();
    },
    600_000,
  );
});
