// The stream controller on the GPU side (ChunkedVolume + the one isosurface
// pipeline): a hydrogen-atom store refined to level 0 gives exactly the
// triangles of the in-core pipeline on the level as one stream (assembled,
// byte-equal to zfpy's), fetching only the chunks the plan needs; fast
// scrubbing aborts stale requests and ends equal to the in-core surface at
// the last value; within a budget smaller than the store, 20 isovalues
// raise no error and the accounted GPU bytes never exceed the budget.
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect } from 'vitest';
import type { GpuContext } from '../../../src/gpu/device.ts';
import { Isosurface } from '../../../src/isosurface/isosurface.ts';
import { assembleLevelStream } from '../../../src/store/assemble.ts';
import { ChunkFetcher } from '../../../src/store/fetch/chunk-fetcher.ts';
import { createChunkStream } from '../../../src/store/gpu-port.ts';
import { chunksNeeded, neighbourhoodRanges } from '../../../src/store/plan.ts';
import { storeForLocation } from '../../../src/store/zarr/node-store.ts';
import { openStore } from '../../../src/store/zarr/open-store.ts';
import { loadZfpStream } from '../../../src/zfp/gpu-stream.ts';
import { meshPositions } from '../../../src/isosurface/vertex-format.ts';
import { shownValueAt } from '../../../src/store/shown-value.ts';
import { VolumeProbe } from '../../../src/zfp/probe.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { runPython, sharedData } from '../../helpers/python.ts';
import { convert, converterPython, zarrPythonStore } from './stores.ts';

const work = mkdtempSync(join(tmpdir(), 'store-stream-gpu-'));
const path = join(work, 'hydrogen.zarr');
const big = join(work, 'gen256.zarr');
beforeAll(() => {
  convert('volumes/hydrogen_atom_128x128x128_float32.raw', path, ['--chunk', '16', '--rate', '8', '--levels', '3']);
  convert('gen:256x256x256', big, ['--chunk', '32', '--rate', '8']);
}, 900_000);
afterAll(() => rmSync(work, { recursive: true, force: true }));

async function inCore(gpu: GpuContext, isos: number[]): Promise<number[]> {
  const s = await openStore(storeForLocation(path), path);
  const L = s.levels[0];
  const chunks = await Promise.all(Array.from({ length: L.chunkCount }, (_, i) => s.readChunk(0, i)));
  const stream = loadZfpStream(
    gpu.device,
    assembleLevelStream(L.layout, (c) => chunks[c]),
    'whole',
  );
  const iso = await Isosurface.create(gpu, stream);
  const out: number[] = [];
  for (const v of isos) out.push((await iso.compute(v)).triangles);
  iso.destroy();
  stream.destroy();
  return out;
}

async function controller(gpu: GpuContext, budget: number, maxInFlight = 8, at = path) {
  const store = await openStore(storeForLocation(at), at);
  const fetcher = new ChunkFetcher(store, { maxInFlight });
  const c = await createChunkStream(store, fetcher, gpu, budget);
  const errors: string[] = [];
  c.onError((e) => errors.push(e.message));
  return { store, fetcher, c, errors };
}

describe('LevelStream on ChunkedVolume', () => {
  gpuTest(
    "a store without range arrays: its first surface fetches the level whole, then its chunk ranges (from the GPU) equal NumPy's over zarr-python's decode and plan the next surface",
    async ({ gpu }) => {
      const other = zarrPythonStore(join(work, 'other.zarr'), [20, 24, 36], 8, 'serializer=ZFPY(mode=2, rate=8), compressors=None');
      const { store, fetcher, c, errors } = await controller(gpu, 256 << 20, 8, other);
      expect(c.chunkRanges(0)).toBeNull();
      expect(c.valueRange).toBeNull();
      await c.setIsovalue(1);
      expect(c.shown?.level).toBe(0);
      expect(c.shown!.stats.triangles).toBeGreaterThan(0);
      const lv = store.levels[0];
      expect(fetcher.counters.bytesFetched).toBe(lv.chunkCount * lv.layout.chunkBytes);
      const ref = JSON.parse(
        converterPython(
          `
import sys, json, zarr
a = zarr.open_array(sys.argv[1], mode='r')[:]
out = []
for cz in range(3):
    for cy in range(3):
        for cx in range(5):
            s = a[cz * 8:(cz + 1) * 8, cy * 8:(cy + 1) * 8, cx * 8:(cx + 1) * 8]
            out += [float(s.min()), float(s.max())]
print(json.dumps(out))
`,
          [other],
        ),
      ) as number[];
      expect(Array.from(c.chunkRanges(0)!)).toEqual(ref);
      expect(c.valueRange).toEqual([Math.min(...ref), Math.max(...ref)]);
      // planned from those ranges now: a surface near the top of the range needs only some chunks
      const iso = 2.6;
      const need = chunksNeeded(neighbourhoodRanges(lv.layout.chunkGrid, c.chunkRanges(0)!), iso);
      expect(need.length).toBeGreaterThan(0);
      expect(need.length).toBeLessThan(lv.chunkCount);
      await c.setIsovalue(iso);
      expect(c.shown?.iso).toBe(iso);
      expect(errors).toEqual([]);
      c.destroy();
    },
  );

  gpuTest('refines to level 0: the in-core triangles, only the needed chunks fetched', async ({ gpu }) => {
    const [ref] = await inCore(gpu, [200]);
    const { store, fetcher, c, errors } = await controller(gpu, 256 << 20);
    const shown: number[] = [];
    c.onShown((s) => shown.push(s.level));
    await c.setIsovalue(200);
    expect(shown).toEqual([2, 1, 0]);
    expect(c.shown!.stats.triangles).toBe(ref);
    expect(ref).toBeGreaterThan(0);
    const needed = await Promise.all(
      store.levels.map(
        async (l, i) =>
          chunksNeeded(neighbourhoodRanges(l.layout.chunkGrid, (await store.readRanges(i))!), 200).length * l.layout.chunkBytes,
      ),
    );
    expect(fetcher.counters.bytesFetched).toBe(needed.reduce((a, b) => a + b, 0));
    expect(fetcher.counters.bytesFetched / store.levels.reduce((a, l) => a + l.storedBytes, 0)).toBeLessThan(0.15);
    expect(errors).toEqual([]);

    // picked values on the step (shown-value.ts): at points of its surface, NumPy's trilinear value over zfpy's
    // decode of level 0 compressed as one stream at the store's rate (zfp codes each block alone); none where
    // no chunk of the step is resident
    const step = c.stream.shown!;
    const mesh = meshPositions(await step.levels[0].surface.readDrawnMesh());
    const n = mesh.length / 3;
    const points = Array.from({ length: 8 }, (_, i) => {
      const v = Math.floor(((i + 0.5) * n) / 8);
      return [mesh[3 * v], mesh[3 * v + 1], mesh[3 * v + 2]] as [number, number, number];
    });
    const probe = await VolumeProbe.create(gpu.device);
    const ours = await Promise.all(points.map((p) => shownValueAt(probe, step, store.levelOffsets, store.levelScales, p)));
    const numpy = JSON.parse(
      runPython(
        `
import sys, json, zfpy, numpy as np
a = np.fromfile(sys.argv[1], dtype=np.float32).reshape(128, 128, 128)
v = zfpy.decompress_numpy(zfpy.compress_numpy(a, rate=8)).astype(np.float64)   # z, y, x
out = []
for p in json.loads(sys.argv[2]):
    lo = [min(int(np.floor(p[a])), 126) for a in range(3)]
    s = 0.0
    for k in range(8):
        c = [lo[a] + ((k >> a) & 1) for a in range(3)]
        s += np.prod([p[a] - lo[a] if (k >> a) & 1 else 1 - (p[a] - lo[a]) for a in range(3)]) * v[c[2], c[1], c[0]]
    out.append(s)
print(json.dumps(out))
`,
        [join(sharedData, 'volumes/hydrogen_atom_128x128x128_float32.raw'), JSON.stringify(points)],
      ),
    );
    ours.forEach((o, i) => {
      expect(o?.level, `point ${points[i].join(', ')}`).toBe(0);
      expect(o!.value).toBeCloseTo(numpy[i], 3);
      // a point of the surface at 200: its value is the isovalue, up to the mesh's float32 positions
      expect(Math.abs(o!.value - 200)).toBeLessThan(1);
    });
    // a corner far from the atom: its chunk holds no surface, so no level of the step has it
    expect(await shownValueAt(probe, step, store.levelOffsets, store.levelScales, [1, 1, 1])).toBeNull();
    probe.destroy();
    c.destroy();
  });

  gpuTest('fast scrubbing aborts stale requests and ends at the in-core surface of the last value', async ({ gpu }) => {
    const [ref] = await inCore(gpu, [30]);
    const { fetcher, c, errors } = await controller(gpu, 256 << 20, 2);
    c.focus = [0, 0, 0];
    const level0 = new Promise<void>((r) =>
      c.onProgress((p) => {
        if (p.level === 0 && p.phase === 'fetching') r();
      }),
    );
    const runs = [c.setIsovalue(1)];
    await level0;
    runs.push(...[200, 2, 150, 4, 100, 8, 30].map((v) => c.setIsovalue(v)));
    await Promise.all(runs);
    expect(fetcher.counters.aborted).toBeGreaterThan(0);
    expect(c.shown).toMatchObject({ level: 0, iso: 30 });
    expect(c.shown!.stats.triangles).toBe(ref);
    expect(errors).toEqual([]);
    c.destroy();
  });

  gpuTest('20 isovalues within a budget several times below the store: no error, accounted GPU bytes within it', async ({ gpu }) => {
    const budget = 6 << 20;
    const { store, c, errors } = await controller(gpu, budget, 8, big);
    const storeBytes = store.levels.reduce((a, l) => a + l.storedBytes, 0);
    expect(storeBytes).toBeGreaterThan(2.5 * budget);
    const [lo, hi] = store.valueRange!;
    const stops: string[] = [];
    c.onProgress((p) => {
      if (p.phase === 'stopped' && p.reason) stops.push(p.reason);
    });
    const levelsShown = new Set<number>();
    for (let i = 0; i < 20; i++) {
      await c.setIsovalue(lo + ((i + 0.5) / 20) * (hi - lo));
      expect(c.shown, stops.join(' | ')).not.toBeNull();
      levelsShown.add(c.shown!.level);
      expect(c.gpuBytes.total).toBeLessThanOrEqual(budget);
    }
    expect(errors).toEqual([]);
    expect(stops.length).toBeGreaterThan(0);
    expect([...levelsShown].length).toBeGreaterThan(0);
    c.destroy();
  });
});
