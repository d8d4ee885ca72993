// `npm run bench:stream -- --codec zstd,blosc,gzip [--size N] [--repeats R]`:
// stores of lossless chunks (issue 28) next to the same volume as a zfp
// store. A generated N^3 uint8 field (default 256 here; the 1024 with
// --size 1024) is written by zarr-python as a 3-level OME-Zarr pyramid in
// 64^3 chunks with each codec, and converted once by our converter into a
// zfp store at rate 8 (64^3 chunks). Measured:
// - CPU: a brick reader alone (fetch, decode with zarrita's codecs, assemble,
//   pad), level 0 whole over localhost: MB/s of voxels. This is one thread,
//   what one of the page's decode workers does (the page runs
//   hardwareConcurrency - 1 of them, up to 4; Node has no Web Workers, so the
//   total over workers is not measured here).
// - GPU: the level's bricks encoded into a pool (ChunkedVolume.put of
//   values, ZfpEncoder.encodeSlot): MB/s of voxels.
// - The level-by-level store stream over HTTP (localhost and the simulated 100 Mbit/s
//   link): time to the first surface (coarsest level) and to level 0, bytes
//   fetched, against the zfp store.
// Median of the repeats after a discarded first; JSON to
// benchmarks/results/stream-codec-swiftshader.json.
import { execFileSync } from 'node:child_process';
import { existsSync } from 'node:fs';
import type { Server } from 'node:http';
import { join } from 'node:path';
import { describeAdapter, type GpuContext } from '../src/gpu/device.ts';
import { ChunkFetcher } from '../src/store/fetch/chunk-fetcher.ts';
import { createChunkStream } from '../src/store/gpu-port.ts';
import { HttpStore } from '../src/store/zarr/http-store.ts';
import { openStore } from '../src/store/zarr/open-store.ts';
import { ChunkedVolume } from '../src/zfp/chunked-volume.ts';
import { encoderFor } from '../src/zfp/encoder.ts';
import { printTable, summarize } from './lib/report.ts';
import { linkStore } from './stream-scale.ts';

const MAKE_STORES = `
import sys, numpy as np, dask.array as da, zarr, numcodecs
from zarr.codecs import ZstdCodec, BloscCodec, GzipCodec
n, out, codec = int(sys.argv[1]), sys.argv[2], sys.argv[3]
def field(block_info=None):
    loc = block_info[None]['array-location']
    z, y, x = np.meshgrid(*[np.arange(a, b, dtype=np.float32) for a, b in loc], indexing='ij')
    s = n / 8.0
    f = np.sin(x / s) * np.cos(y / (1.3 * s)) + np.sin(z / (0.9 * s) + x / (3 * s)) + 0.1 * np.sin(x / 3.0 + y / 5.0)
    return np.clip((f + 2.1) * 60, 0, 255).astype(np.uint8)
v = da.map_blocks(field, chunks=((64,) * (n // 64),) * 3, dtype=np.uint8)
compressor = {'zstd': ZstdCodec(level=3), 'blosc': BloscCodec(cname='lz4', clevel=5, shuffle='bitshuffle'), 'gzip': GzipCodec(level=5)}[codec]
g = zarr.open_group(out, mode='w', zarr_format=3)
for i in range(3):
    arr = g.create_array(str(i), shape=v.shape, chunks=(64, 64, 64), dtype='uint8', compressors=compressor)
    da.store(v, arr, lock=False)
    v = da.coarsen(np.mean, v.astype(np.float32), {0: 2, 1: 2, 2: 2}).round().astype(np.uint8).rechunk(64)
axes = [{'name': a, 'type': 'space'} for a in 'zyx']
g.attrs['ome'] = {'version': '0.5', 'multiscales': [{'axes': axes, 'datasets': [
    {'path': str(i), 'coordinateTransformations': [{'type': 'scale', 'scale': [2.0 ** i] * 3}]} for i in range(3)]}]}
`;

export interface CodecBenchOptions {
  root: string;
  folder: string;
  port: number;
  server: Server;
  size: number;
  repeats: number;
  codecs: string[];
  links: string[];
  budgetBytes: number;
}

function makeStores(o: CodecBenchOptions): string[] {
  const python = join(o.root, '.venv-converter/bin/python');
  const names: string[] = [];
  for (const codec of o.codecs) {
    const name = `codec-${codec}-${o.size}.zarr`;
    if (!existsSync(join(o.folder, name, 'zarr.json'))) {
      console.log(`writing ${name} with zarr-python`);
      execFileSync(python, ['-c', MAKE_STORES, String(o.size), join(o.folder, name), codec], { stdio: 'inherit' });
    }
    names.push(name);
  }
  const zfp = `codec-zfp-${o.size}.zarr`;
  if (!existsSync(join(o.folder, zfp, 'zarr.json'))) {
    console.log(`converting ${names[0]} -> ${zfp} (rate 8)`);
    execFileSync(
      process.execPath,
      [
        join(o.root, 'scripts/convert.mjs'),
        `${join(o.folder, names[0])}:0`,
        '--out',
        join(o.folder, zfp),
        '--rate',
        '8',
        '--chunk',
        '64',
        '--levels',
        '3',
        '--quiet',
      ],
      { stdio: 'inherit' },
    );
  }
  return [...names, zfp];
}

const mb = (bytes: number, ms: number) => bytes / 2 ** 20 / (ms / 1000);

export async function codecBench(gpu: GpuContext, o: CodecBenchOptions): Promise<Record<string, unknown>[]> {
  const names = makeStores(o);
  const rows: (string | number)[][] = [];
  const records: Record<string, unknown>[] = [];
  const encoder = await encoderFor(gpu.device);
  for (const name of names) {
    const url = `http://127.0.0.1:${o.port}/stores/${name}`;
    // CPU: level 0's bricks, one thread (a worker's share)
    const cpu: number[] = [];
    const gpuEncode: number[] = [];
    let voxelBytes = 0;
    let lossless = false;
    for (let r = 0; r < o.repeats; r++) {
      const store = await openStore(new HttpStore(url), url);
      lossless = store.source !== null;
      if (!lossless) break;
      const lv = store.levels[0];
      const bricks: Uint8Array[] = [];
      const t0 = performance.now();
      for (let i = 0; i < lv.chunkCount; i++) bricks.push(await store.readChunk(0, i));
      cpu.push(performance.now() - t0);
      voxelBytes = lv.layout.dims.reduce((a, b) => a * b, 1); // uint8: one byte per voxel
      const pool = ChunkedVolume.create(gpu, lv.layout, { poolChunks: lv.chunkCount, encoder });
      await gpu.device.queue.onSubmittedWorkDone();
      const t1 = performance.now();
      bricks.forEach((b, i) => pool.put(i, b));
      await gpu.device.queue.onSubmittedWorkDone();
      gpuEncode.push(performance.now() - t1);
      pool.destroy();
    }
    for (const link of o.links) {
      const first: number[] = [];
      const full: number[] = [];
      let bytes = 0;
      let triangles = 0;
      for (let r = 0; r < o.repeats; r++) {
        const metered = linkStore(url, link);
        const t0 = performance.now();
        const store = await openStore(metered, url);
        const fetcher = new ChunkFetcher(store);
        const c = await createChunkStream(store, fetcher, gpu, o.budgetBytes);
        let t1 = Number.NaN;
        c.onShown(() => {
          if (Number.isNaN(t1)) t1 = performance.now();
        });
        await c.setIsovalue(127.5);
        const t2 = performance.now();
        if (c.shown?.level !== 0) throw new Error(`${name}: stopped at level ${c.shown?.level} (raise --budget-mb)`);
        triangles = c.shown.stats.triangles;
        first.push(t1 - t0);
        full.push(t2 - t0);
        bytes = metered.meter.bytes;
        c.destroy();
      }
      const f = summarize(first.slice(1));
      const g = summarize(full.slice(1));
      const c = cpu.length > 1 ? summarize(cpu.slice(1)).median : Number.NaN;
      const e = gpuEncode.length > 1 ? summarize(gpuEncode.slice(1)).median : Number.NaN;
      rows.push([
        name,
        link,
        lossless ? mb(voxelBytes, c).toFixed(1) : '(zfp: none)',
        lossless ? mb(voxelBytes, e).toFixed(1) : '(zfp: none)',
        f.median,
        g.median,
        (bytes / 2 ** 20).toFixed(2),
        triangles,
      ]);
      records.push({
        store: name,
        link,
        lossless,
        level0VoxelBytes: voxelBytes,
        cpuDecodeMs: lossless ? summarize(cpu.slice(1)) : null,
        cpuDecodeMBps: lossless ? mb(voxelBytes, c) : null,
        gpuEncodeMs: lossless ? summarize(gpuEncode.slice(1)) : null,
        gpuEncodeMBps: lossless ? mb(voxelBytes, e) : null,
        firstSurfaceMs: f,
        fullSurfaceMs: g,
        bytesFetched: bytes,
        triangles,
        iso: 127.5,
      });
    }
  }
  printTable(
    `bench:stream --codec, ${describeAdapter(gpu.adapter)}, median of ${o.repeats - 1} after a discarded first; a generated ${o.size}^3 uint8 field, 3 levels, 64^3 chunks; lossless stores compressed on the GPU at rate 8; zfp store converted at rate 8; iso 127.5; budget ${o.budgetBytes / 2 ** 20} MiB`,
    ['store', 'link', 'CPU decode MB/s (1 thread)', 'GPU encode MB/s', 'first surface ms', 'level 0 ms', 'fetched MiB', 'triangles'],
    rows,
  );
  return records;
}
