// Prefetch of a series' next time point (src/store/series/prefetch.ts),
// headless on the GPU: a series written by NumPy and converted with
// `convert --time` (128^3 x 3, 16^3 chunks, four levels, range arrays per
// time point). Time point 0 is shown level by level; time point 1 is
// fetched ahead from time point 0's plan with time point 1's range arrays,
// then shown by a session that takes it over. Truth from outside: the
// chunks time point 1 needs, by NumPy over its range arrays as zarr-python
// reads them (a chunk is needed iff lo < iso <= hi over its 27-chunk
// neighbourhood, every level from the coarsest to level 0, as the level
// planner draws them), and their bytes as the chunk files on disk hold
// them. The session fetches nothing more and reads no metadata once it
// takes the prefetch over; with a bound too small for the time point, the
// rest comes when it is shown, and still no chunk comes twice. The surface
// is the one a session without prefetch makes.
import { execFileSync } from 'node:child_process';
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect } from 'vitest';
import type { ChunkIndex } from '../../../src/store/types.ts';
import { SeriesPrefetch } from '../../../src/store/series/prefetch.ts';
import { StoreSession } from '../../../src/store/session.ts';
import { storeForLocation } from '../../../src/store/zarr/node-store.ts';
import { openStore } from '../../../src/store/zarr/open-store.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { repoRoot, runPython } from '../../helpers/python.ts';
import { converterPython } from './stores.ts';

const ISO = 0.5;
const work = mkdtempSync(join(tmpdir(), 'series-prefetch-'));
const store = join(work, 'series.zarr');
/** Per level (coarsest first): the chunks time point 1 needs and their bytes on disk. */
let expected: { level: number; chunks: number[]; bytes: number }[];

beforeAll(() => {
  runPython(
    `
import sys, numpy as np
d, n, T = sys.argv[1], 128, 3
ax = np.arange(n, dtype=np.float32)
z, y, x = np.meshgrid(ax, ax, ax, indexing='ij')
for t in range(T):
    cx = n * (0.3 + 0.2 * t)
    np.exp(-((x - cx) ** 2 + (y - 60) ** 2 + (z - 68) ** 2) / 14.0 ** 2).astype(np.float32).tofile(f'{d}/step_{t}_{n}x{n}x{n}_float32.raw')
`,
    [work],
  );
  execFileSync(
    process.execPath,
    [
      'scripts/convert.mjs',
      join(work, 'step_*_128x128x128_float32.raw'),
      '--time',
      '--out',
      store,
      '--chunk',
      '16',
      '--rate',
      '8',
      '--quiet',
    ],
    { cwd: repoRoot, stdio: 'pipe', timeout: 300_000 },
  );
  expected = JSON.parse(
    converterPython(
      `
import sys, os, json, numpy as np, zarr
root, t, iso = sys.argv[1], int(sys.argv[2]), np.float32(sys.argv[3])
g = zarr.open_group(root, mode='r')
levels = [d['path'] for d in g.attrs['ome']['multiscales'][0]['datasets']]
out = []
for L in reversed(range(len(levels))):
    r = np.asarray(zarr.open_array(os.path.join(root, 'ranges', str(L)), mode='r')[t])   # [cz, cy, cx, 2]
    lo, hi = r[..., 0].astype(np.float64), r[..., 1].astype(np.float64)
    pad = lambda a, v: np.pad(a, 1, constant_values=v)
    plo, phi = pad(lo, np.inf), pad(hi, -np.inf)
    cz, cy, cx = lo.shape
    nlo = np.full(lo.shape, np.inf); nhi = np.full(lo.shape, -np.inf)
    for dz in range(3):
        for dy in range(3):
            for dx in range(3):
                nlo = np.minimum(nlo, plo[dz:dz + cz, dy:dy + cy, dx:dx + cx])
                nhi = np.maximum(nhi, phi[dz:dz + cz, dy:dy + cy, dx:dx + cx])
    need = (nlo < iso) & (iso <= nhi)
    chunks, size = [], 0
    for (z, y, x) in zip(*np.nonzero(need)):
        chunks.append(int(x + cx * (y + cy * z)))
        size += os.path.getsize(os.path.join(root, levels[L], 'c', str(t), str(z), str(y), str(x)))
    out.append({'level': L, 'chunks': sorted(chunks), 'bytes': size})
print(json.dumps(out))
`,
      [store, '1', String(ISO)],
    ),
  );
}, 300_000);
afterAll(() => rmSync(work, { recursive: true, force: true }));

async function session(
  gpu: Parameters<typeof StoreSession.open>[0],
  t: number,
  prepared?: Parameters<typeof StoreSession.open>[3]['prepared'],
) {
  const s = await StoreSession.open(gpu, storeForLocation(store), store, { open: { time: t }, budget: 64 * 2 ** 20, prepared });
  s.stream.snapshots = false;
  return s;
}

/** Time point 1 fetched ahead from `shown`'s plan, within `capacityBytes`. */
function ahead(prefetch: SeriesPrefetch, shown: StoreSession, capacityBytes?: number) {
  const source = storeForLocation(store);
  prefetch.start(source, {
    time: 1,
    open: (metered) => openStore(metered, store, { time: 1 }),
    wanted: (needsAt) => shown.stream.wantedAhead(needsAt),
    levels: shown.store.levels.map((_, L) => L),
    capacityBytes,
  });
  return source;
}

const chunksOf = (s: StoreSession) => s.store.levels.map((_, L) => s.fetched.chunks(L));
const trianglesOf = (s: StoreSession) => s.stream.shown!.levels.map((l) => [l.level, l.stats.triangles]);

describe('series prefetch', () => {
  gpuTest('time point 1 fetched ahead: the chunks NumPy says it needs, each once, no request once shown', async ({ gpu }) => {
    const t0 = await session(gpu, 0);
    const plain = await session(gpu, 1);
    try {
      await t0.stream.setIsovalue(ISO);
      await plain.stream.setIsovalue(ISO);
      const prefetch = new SeriesPrefetch();
      const source = ahead(prefetch, t0);
      const prepared = await prefetch.take(1, source);
      expect(prepared).not.toBeNull();
      const p = prepared!;
      // a plan with every range array read: what it wants is what time point 1 needs, coarsest level first
      const wanted = expected.flatMap((e) => e.chunks.map((c) => `${e.level}:${c}`));
      expect(p.state).toMatchObject({
        time: 1,
        wanted: wanted.length,
        asked: wanted.length,
        arrived: wanted.length,
        full: false,
        done: true,
        error: null,
      });
      expect(p.state.bytes).toBe(expected.reduce((a, e) => a + e.bytes, 0));
      for (const e of expected) expect(p.fetched.chunks(e.level)).toBe(e.chunks.length);
      const requests = p.metered.meter.requests;
      const bytes = p.fetcher.counters.bytesFetched;
      const t1 = await session(gpu, 1, p);
      try {
        await t1.stream.setIsovalue(ISO);
        // nothing more over the wire: no metadata, no range array, no chunk
        expect(p.metered.meter.requests).toBe(requests);
        expect(t1.fetcher.counters.bytesFetched).toBe(bytes);
        expect(t1.fetched.bytes()).toBe(expected.reduce((a, e) => a + e.bytes, 0));
        expect(chunksOf(t1)).toEqual(chunksOf(plain));
        // the same surface as a session that fetched it all itself, drawn from the chunks NumPy named
        expect(trianglesOf(t1)).toEqual(trianglesOf(plain));
        for (const l of t1.stream.shown!.levels) {
          const e = expected.find((x) => x.level === l.level)!;
          expect([...l.drawn].sort((a: ChunkIndex, b: ChunkIndex) => a - b)).toEqual(e.chunks);
        }
      } finally {
        t1.close();
      }
    } finally {
      t0.close();
      plain.close();
    }
  });

  gpuTest('a bound too small for the time point: its first chunks ahead, the rest when shown, none twice', async ({ gpu }) => {
    const t0 = await session(gpu, 0);
    try {
      await t0.stream.setIsovalue(ISO);
      const prefetch = new SeriesPrefetch();
      const total = expected.reduce((a, e) => a + e.bytes, 0);
      const source = ahead(prefetch, t0, Math.floor(total / 3));
      const p = (await prefetch.take(1, source))!;
      expect(p.state.full).toBe(true);
      expect(p.state.asked).toBeGreaterThan(0);
      expect(p.state.asked).toBeLessThan(p.state.wanted);
      expect(p.state.bytes).toBeLessThanOrEqual(Math.floor(total / 3));
      // coarse steps first: the coarsest level's chunks are all there
      const coarsest = expected[0];
      expect(p.fetched.chunks(coarsest.level)).toBe(coarsest.chunks.length);
      const t1 = await session(gpu, 1, p);
      try {
        await t1.stream.setIsovalue(ISO);
        expect(t1.stream.shown?.final).toBe(true);
        expect(t1.fetched.bytes()).toBe(total);
        expect(t1.fetcher.counters.bytesFetched).toBe(total);
      } finally {
        t1.close();
      }
    } finally {
      t0.close();
    }
  });

  gpuTest('a prefetch of another time point is let go; a store that cannot be opened is made when shown', async ({ gpu }) => {
    const t0 = await session(gpu, 0);
    try {
      await t0.stream.setIsovalue(ISO);
      const prefetch = new SeriesPrefetch();
      const source = ahead(prefetch, t0);
      expect(await prefetch.take(2, source)).toBeNull();
      expect(prefetch.state).toBeNull();
      prefetch.start(source, {
        time: 7,
        open: (metered) => openStore(metered, store, { time: 7 }),
        wanted: (needsAt) => t0.stream.wantedAhead(needsAt),
        levels: [0],
      });
      expect(await prefetch.take(7, source)).toBeNull();
    } finally {
      t0.close();
    }
  });
});
