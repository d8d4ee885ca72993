// Chunk ranges learnt as chunks arrive (src/store/learnt-ranges.ts, issue
// 37). The rule against plan.ts's range-array rule on random ranges with
// unknown chunks; then a store of lossless chunks written by zarr-python
// (uint8, structure in the middle, empty space around, partial edge
// chunks), streamed by the view on the GPU: every learnt range equals the
// ranges sidecar that `convert --ranges-only` writes (zfpy's decode of each
// brick at the store's rate), and a second isovalue fetches no brick whose
// learnt neighbourhood excludes it.
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, it } from 'vitest';
import { ChunkFetcher } from '../../../src/store/fetch/chunk-fetcher.ts';
import { chunkedGpu, createChunkStream, storeEncoder } from '../../../src/store/gpu-port.ts';
import { LearntRanges, MAX_LEARNT_CHUNKS, SESSION_RANGES_BYTES, sessionRanges } from '../../../src/store/learnt-ranges.ts';
import { chunkNeeded, neighbourhoodRanges } from '../../../src/store/plan.ts';
import { cameraForBox, cameraFromView, fitBox0, sceneRadiusOf } from '../../../src/store/view/camera.ts';
import { DEFAULT_VIEWPORT } from '../../../src/store/view/view-request.ts';
import { StoreStream } from '../../../src/store/stream/store-stream.ts';
import { storeForLocation } from '../../../src/store/zarr/node-store.ts';
import { openStore } from '../../../src/store/zarr/open-store.ts';
import { openRangesSidecar } from '../../../src/store/zarr/ranges-sidecar.ts';
import type { ChunkedVolume } from '../../../src/zfp/chunked-volume.ts';
import type { Isosurface } from '../../../src/isosurface/isosurface.ts';
import type { IsosurfaceStats } from '../../../src/isosurface/types.ts';
import { mulberry32 } from '../../../src/util/random.ts';
import { repoRoot } from '../../helpers/python.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { cli, converterPython } from './stores.ts';

const work = mkdtempSync(join(tmpdir(), 'learnt-ranges-'));
const storePath = join(work, 'blob.zarr');
const sidecarPath = join(work, 'blob-ranges.zarr');
const DIMS: [number, number, number] = [120, 104, 90]; // x, y, z: partial 16^3 chunks on every axis
beforeAll(() => {
  // uint8, zstd, 16^3 chunks: a noisy ball of radius 16 at the centre, zeros around it
  converterPython(
    `
import sys, numpy as np, zarr
from zarr.codecs import ZstdCodec
x, y, z = ${JSON.stringify(DIMS)}
g = np.mgrid[0:z, 0:y, 0:x].astype('float64')
r = np.sqrt((g[0] - z / 2) ** 2 + (g[1] - y / 2) ** 2 + (g[2] - x / 2) ** 2)
rng = np.random.default_rng(5)
v = np.where(r < 16, 120 + 100 * np.cos(r / 4) + rng.uniform(-20, 20, r.shape), 0).clip(0, 255).astype('uint8')
a = zarr.create_array(sys.argv[1], shape=v.shape, chunks=(16, 16, 16), dtype='uint8', compressors=[ZstdCodec()], overwrite=True)
a[:] = v
`,
    [storePath],
  );
  execFileSync(
    process.execPath,
    [join(repoRoot, 'scripts/convert.mjs'), storePath, '--out', sidecarPath, '--ranges-only', '--rate', '8', '--quiet'],
    {
      timeout: 600_000,
      stdio: 'pipe',
    },
  );
}, 600_000);
afterAll(() => rmSync(work, { recursive: true, force: true }));

describe('LearntRanges', () => {
  it("needs = plan.ts's rule over the same ranges, unknown chunks (NaN) making their neighbourhood needed", () => {
    const rnd = mulberry32(11);
    for (const grid of [
      [1, 1, 1],
      [5, 1, 1],
      [4, 3, 2],
      [7, 6, 5],
    ] as [number, number, number][]) {
      const n = grid[0] * grid[1] * grid[2];
      const learnt = new LearntRanges([grid]);
      const ranges = new Float32Array(2 * n).fill(Number.NaN);
      for (let c = 0; c < n; c++) {
        const u = rnd();
        if (u < 0.25) continue; // unknown
        // some empty chunks (no finite value: min > max), the rest random
        const [lo, hi] = u < 0.35 ? [3.4028234663852886e38, -3.4028234663852886e38] : [10 * rnd(), 10 + 10 * rnd()].sort((a, b) => a - b);
        learnt.record(0, c, lo, hi);
        ranges[2 * c] = lo;
        ranges[2 * c + 1] = hi;
      }
      const nb = neighbourhoodRanges(grid, ranges);
      for (const iso of [-1, 0, 5, 9.99, 10, 12.5, 20, 30])
        for (let c = 0; c < n; c++) expect(learnt.needs(0, iso, c), `grid ${grid} iso ${iso} chunk ${c}`).toBe(chunkNeeded(nb, iso, c));
      expect(learnt.knownCount(0)).toBe(ranges.filter((v, i) => i % 2 === 0 && !Number.isNaN(v)).length);
    }
  });

  it('a level with more chunks than MAX_LEARNT_CHUNKS is not learnt (every chunk needed); a chunk outside its level is refused', () => {
    const big = new LearntRanges([
      [2, 2, 2],
      [MAX_LEARNT_CHUNKS, 2, 1],
    ]);
    expect(big.learns(0)).toBe(true);
    expect(big.learns(1)).toBe(false);
    big.record(1, 5, 0, 1);
    expect(big.has(1, 5)).toBe(false);
    expect(big.needs(1, 100, 5)).toBe(true);
    expect(() => big.record(0, 8, 0, 1)).toThrow(/chunk 8 outside level 0/);
    big.record(0, 3, -2, 7);
    expect(big.valueRange()).toEqual([-2, 7]);
  });
});

describe('sessionRanges', () => {
  it('the same store and values get the ranges learnt before; other chunk grids start afresh', () => {
    const grids: [number, number, number][] = [[3, 2, 1]];
    const a = sessionRanges('s.zarr|8|0|0', grids);
    a.record(0, 4, 1, 2);
    expect(sessionRanges('s.zarr|8|0|0', grids)).toBe(a);
    expect(sessionRanges('s.zarr|8|0|0', grids).get(0, 4)).toEqual([1, 2]);
    expect(sessionRanges('s.zarr|6|0|0', grids)).not.toBe(a);
    const other = sessionRanges('s.zarr|8|0|0', [[3, 2, 2]]);
    expect(other).not.toBe(a);
    expect(other.has(0, 4)).toBe(false);
    // small stores: every one kept (the time points of a series, each its own)
    for (let t = 0; t < 50; t++) sessionRanges(`series|8|${t}`, grids).record(0, 1, t, t + 1);
    expect(sessionRanges('s.zarr|8|0|0', [[3, 2, 2]])).toBe(other);
    for (let t = 0; t < 50; t++) expect(sessionRanges(`series|8|${t}`, grids).get(0, 1)).toEqual([t, t + 1]);
  });

  it('bounded in bytes: the least recently opened go first, the last 4 always kept', () => {
    // 2 Mi chunks: 16 MiB of ranges once one is learnt
    const big: [number, number, number][] = [[128, 128, 128]];
    const made = ['a', 'b', 'c', 'd', 'e', 'f'].map((k) => {
      const r = sessionRanges(`big|${k}`, big);
      r.record(0, 7, 0, 1);
      expect(r.bytes).toBe(16 * 2 ** 20);
      return r;
    });
    // 96 MiB > SESSION_RANGES_BYTES: a and b were let go (64 MiB left), c..f kept
    expect(SESSION_RANGES_BYTES).toBe(64 * 2 ** 20);
    expect(sessionRanges('big|f', big)).toBe(made[5]);
    expect(sessionRanges('big|c', big)).toBe(made[2]);
    expect(sessionRanges('big|a', big)).not.toBe(made[0]);
  });
});

describe('ranges learnt by the view stream on the GPU', () => {
  gpuTest(
    "a store of lossless chunks: each learnt range = the sidecar's (zfpy at the store's rate); a second isovalue skips what they exclude",
    async ({ gpu }) => {
      const store = await openStore(storeForLocation(storePath), storePath, { rate: 8 });
      expect(store.source).toBeTruthy();
      expect(store.levels.length).toBe(1);
      const sidecar = await openRangesSidecar(storeForLocation(sidecarPath), sidecarPath, { bytes: 0, requests: 0 });
      expect(sidecar.rate).toBe(8);
      const truth = await sidecar.read(0);
      const port = chunkedGpu(gpu, undefined, await storeEncoder(gpu, store));
      const fetcher = new ChunkFetcher(store, { maxInFlight: 4 });
      const fetched: number[] = [];
      // every chunk handed to the stream, fetched or from the fetcher's cache of bytes
      fetcher.onChunk((_L, c) => fetched.push(c));
      const stream = await StoreStream.byView<ChunkedVolume, IsosurfaceStats, Isosurface>(store, fetcher, port, 64 << 20);
      const layout = store.levels[0].layout;
      const box = fitBox0(layout, 0);
      const camera = cameraFromView(
        cameraForBox(box, store.voxelSize, DEFAULT_VIEWPORT).state,
        DEFAULT_VIEWPORT,
        sceneRadiusOf(box, store.voxelSize),
      );
      await stream.setView({ camera, tolerancePx: 1.5 });

      // the first isovalue: every brick is unknown, so every brick in view is fetched
      await stream.setIsovalue(60.5);
      await stream.learnSettled();
      const chunks = layout.chunkGrid[0] * layout.chunkGrid[1] * layout.chunkGrid[2];
      expect(stream.shown?.final).toBe(true);
      expect(new Set(fetched).size).toBe(chunks);
      expect(stream.learnt.knownCount(0)).toBe(chunks);
      for (let c = 0; c < chunks; c++) {
        const got = stream.learnt.get(0, c)!;
        // a brick of zeros: the sidecar says [0, 0] like the GPU's decode
        expect(got, `brick ${c}`).toEqual([truth[2 * c], truth[2 * c + 1]]);
      }

      // a second isovalue inside the ball only: the bricks of empty space around it are neither drawn nor fetched again
      fetched.length = 0;
      const pool = stream.levels[0].volume!;
      for (let c = 0; c < chunks; c++) pool.evict(c);
      const iso2 = 180.5;
      await stream.setIsovalue(iso2);
      const nb = neighbourhoodRanges(layout.chunkGrid, truth);
      const expected = Array.from({ length: chunks }, (_, c) => c).filter((c) => chunkNeeded(nb, iso2, c));
      expect(expected.length).toBeGreaterThan(0);
      expect(expected.length).toBeLessThan(chunks / 2);
      expect([...new Set(fetched)].sort((a, b) => a - b)).toEqual(expected);
      expect(stream.shown?.levels[0].stats.triangles).toBeGreaterThan(100);
      stream.destroy();
      store.close?.();
    },
    300_000,
  );
});

describe('ranges learnt level by level (the stream controller)', () => {
  gpuTest(
    "level by level: the same learnt ranges (= the sidecar's), kept for the store; a controller opened again fetches only the bricks the next isovalue needs",
    async ({ gpu }) => {
      const store = await openStore(storeForLocation(storePath), storePath, { rate: 8 });
      const truth = await (await openRangesSidecar(storeForLocation(sidecarPath), sidecarPath, { bytes: 0, requests: 0 })).read(0);
      const port = chunkedGpu(gpu, undefined, await storeEncoder(gpu, store));
      const first = await createChunkStream(store, new ChunkFetcher(store, { maxInFlight: 4 }), port, 64 << 20);
      await first.setIsovalue(60.5);
      const layout = store.levels[0].layout;
      const chunks = layout.chunkGrid[0] * layout.chunkGrid[1] * layout.chunkGrid[2];
      expect(first.shown?.level).toBe(0);
      expect(first.learnt.knownCount(0)).toBe(chunks);
      for (let c = 0; c < chunks; c++) expect(first.learnt.get(0, c), `brick ${c}`).toEqual([truth[2 * c], truth[2 * c + 1]]);
      expect(first.chunkRanges(0)).toEqual(truth);
      first.destroy();
      // opened again with what was learnt (the page keeps it per store for the session): nothing resident, yet
      // only the bricks the isovalue's neighbourhood rule needs are fetched
      const fetcher = new ChunkFetcher(store, { maxInFlight: 4 });
      const fetched: number[] = [];
      fetcher.onChunk((_L, c) => fetched.push(c));
      const again = await createChunkStream(store, fetcher, port, 64 << 20, { learnt: first.learnt });
      const iso2 = 180.5;
      await again.setIsovalue(iso2);
      const nb = neighbourhoodRanges(layout.chunkGrid, truth);
      const expected = Array.from({ length: chunks }, (_, c) => c).filter((c) => chunkNeeded(nb, iso2, c));
      expect([...new Set(fetched)].sort((a, b) => a - b)).toEqual(expected);
      expect(again.shown?.stats.triangles).toBeGreaterThan(100);
      again.destroy();
      store.close?.();
    },
    300_000,
  );
});

describe('extract --save-ranges: what the surfaces learnt, as a ranges sidecar', () => {
  it("written by a view's surfaces: zarr-python reads it; every known brick = zfpy's; a later run with it fetches only the bricks its isovalue needs", () => {
    const saved = join(work, 'learnt.zarr');
    const json = join(work, 'learn.json');
    const box = `0,0,0,${DIMS.map((n) => n - 1).join(',')}`;
    const r = cli('extract', storePath, '--rate', '8', '--iso', '60.5', '--view-box', box, '--save-ranges', saved, '--json', json);
    expect(r.status, r.stderr).toBe(0);
    const rec = JSON.parse(readFileSync(json, 'utf8'));
    const bricks = DIMS.reduce((a, n) => a * Math.ceil(n / 16), 1);
    expect(rec.savedRanges).toEqual({ path: saved, known: bricks, bricks });
    // read back by zarr-python, compared with the converter's sidecar (zfpy at rate 8)
    const compared = converterPython(
      `
import sys, json, numpy as np, zarr
a = zarr.open_group(sys.argv[1], mode='r')
b = zarr.open_group(sys.argv[2], mode='r')
x, y = a['ranges/0'][...], b['ranges/0'][...]
known = ~np.isnan(x[..., 0])
info = dict(a.attrs)['zfpzarr_ranges']
print(json.dumps({'shape': list(x.shape), 'known': int(known.sum()), 'equal': bool((x[known] == y[known]).all()), 'rate': info['rate'], 'levels': info['levels']}))
`,
      [saved, sidecarPath],
    );
    const c = JSON.parse(compared);
    expect(c.shape).toEqual([...DIMS.map((n) => Math.ceil(n / 16)).reverse(), 2]);
    expect(c.known).toBe(bricks);
    expect(c.equal).toBe(true);
    expect(c.rate).toBe(8);
    expect(c.levels).toEqual([{ path: '', brick: 16, grid: DIMS.map((n) => Math.ceil(n / 16)), dims: DIMS }]);

    // used as --ranges: the bricks the isovalue needs and no other, the same triangles as without it
    const withRanges = join(work, 'with.json');
    const without = join(work, 'without.json');
    const a = cli('extract', storePath, '--rate', '8', '--iso', '180.5', '--level', '0', '--ranges', saved, '--json', withRanges);
    expect(a.status, a.stderr).toBe(0);
    expect(a.stderr).toMatch(/per-brick ranges from .*learnt.zarr \(rate 8\)/);
    const b = cli('extract', storePath, '--rate', '8', '--iso', '180.5', '--level', '0', '--json', without);
    expect(b.status, b.stderr).toBe(0);
    const ra = JSON.parse(readFileSync(withRanges, 'utf8'));
    const rb = JSON.parse(readFileSync(without, 'utf8'));
    expect(ra.isosurfaces[0].triangles).toBe(rb.isosurfaces[0].triangles);
    expect(ra.isosurfaces[0].triangles).toBeGreaterThan(100);
    expect(ra.store.chunks).toBeLessThan(rb.store.chunks / 2);

    // a zfp store has no sidecar to save; a folder that is not a sidecar is not overwritten
    const zfp = cli('extract', 'default', '--iso', '0.5', '--save-ranges', join(work, 'x.zarr'));
    expect(zfp.status).toBe(2);
    expect(zfp.stderr).toMatch(/--save-ranges is for a Zarr store of lossless chunks/);
    const clash = cli('extract', storePath, '--rate', '8', '--iso', '60.5', '--level', '0', '--save-ranges', storePath);
    expect(clash.status).toBe(1);
    expect(clash.stderr).toMatch(/exists and is not a ranges sidecar/);
  }, 300_000);
});
