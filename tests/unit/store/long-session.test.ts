// A long session: 500 isovalues scrubbed over a store (bursts of requests,
// newest wins, refinement coarse to fine each time) and 10 switches between
// stores and in-core volumes. The GPU bytes held (a wrapper around
// createBuffer/destroy, checked at every allocation) never pass the budget,
// closing a store or a volume gives back every byte, the CPU cache of chunks
// stays under its bound, and the last surface of the scrub equals a fresh
// open's at the same isovalue (pools grown and shrunk along the way keep
// their chunks right). Refined by the view (StoreStream, snapshots included):
// camera moves and isovalues landing mid-refinement at a budget that binds,
// every allocation within it, every byte back.
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect } from 'vitest';
import type { GpuContext } from '../../../src/gpu/device.ts';
import { Isosurface } from '../../../src/isosurface/isosurface.ts';
import { ChunkFetcher } from '../../../src/store/fetch/chunk-fetcher.ts';
import { chunkedGpu, createChunkStream } from '../../../src/store/gpu-port.ts';
import { cameraForBox, cameraFromView, fitBox0, sceneRadiusOf } from '../../../src/store/view/camera.ts';
import { DEFAULT_VIEWPORT } from '../../../src/store/view/view-request.ts';
import { StoreStream } from '../../../src/store/stream/store-stream.ts';
import { storeForLocation } from '../../../src/store/zarr/node-store.ts';
import { openStore } from '../../../src/store/zarr/open-store.ts';
import { mulberry32 } from '../../../src/util/random.ts';
import { openDefaultVolume } from '../../../src/volume/open-volume.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { countBuffers } from '../../helpers/gpu-memory.ts';
import { convert } from './stores.ts';

const work = mkdtempSync(join(tmpdir(), 'store-long-'));
const hydrogen = join(work, 'hydrogen.zarr');
const neghip = join(work, 'neghip.zarr');
const MiB = 2 ** 20;
const BUDGET = 24 * MiB;
const CPU_CACHE = 2 * MiB;

beforeAll(() => {
  convert('volumes/hydrogen_atom_128x128x128_float32.raw', hydrogen, ['--chunk', '16', '--rate', '8', '--levels', '4']);
  convert('volumes/neghip_66x66x66_uint8.raw', neghip, ['--chunk', '16', '--rate', '8', '--shard', '2']);
}, 900_000);
afterAll(() => rmSync(work, { recursive: true, force: true }));

async function openStream(gpu: GpuContext, at: string) {
  const store = await openStore(storeForLocation(at), at);
  const fetcher = new ChunkFetcher(store, { maxInFlight: 4, cacheBytes: CPU_CACHE });
  const c = await createChunkStream(store, fetcher, gpu, BUDGET);
  const errors: string[] = [];
  c.onError((e) => errors.push(e.message));
  return { store, fetcher, c, errors };
}

describe('a long session', () => {
  gpuTest(
    '500 isovalues and 10 switches: never above the budget, every byte back after closing, the CPU cache bounded',
    async ({ gpu }) => {
      // the device's shared GPU encoder is made on first use and kept (like its pipelines): made before counting
      (await openDefaultVolume(gpu.device, {})).stream.destroy();
      const count = countBuffers(gpu.device);
      const base = count.live;
      let over = 0;
      count.onAllocate = (live) => {
        if (live - base > BUDGET) over = Math.max(over, live - base);
      };
      const random = mulberry32(7);
      try {
        // 500 isovalues over the hydrogen atom (values 0..~255), in bursts of 5 (only the last of each awaited)
        const s = await openStream(gpu, hydrogen);
        const stops: string[] = [];
        s.c.onProgress((p) => {
          if (p.phase === 'stopped') stops.push(`${p.level}: ${p.reason}`);
        });
        let last = 0;
        for (let i = 0; i < 500; i++) {
          last = 1 + random() * 200;
          const run = s.c.setIsovalue(last);
          if (i % 5 === 4) await run;
          expect(s.fetcher.counters.cacheBytes).toBeLessThanOrEqual(CPU_CACHE);
        }
        expect(s.errors).toEqual([]);
        expect(stops).toEqual([]);
        expect(s.c.shown?.iso).toBe(last);
        expect(s.c.shown?.level).toBe(0);
        const scrubbed = s.c.shown!.stats.triangles;
        s.c.destroy();
        expect(count.live).toBe(base);
        const fresh = await openStream(gpu, hydrogen);
        await fresh.c.setIsovalue(last);
        expect(fresh.c.shown!.stats.triangles).toBe(scrubbed);
        fresh.c.destroy();
        expect(count.live).toBe(base);

        // 10 switches: stores and in-core volumes in turn, a few isovalues each
        for (let k = 0; k < 10; k++) {
          if (k % 3 === 2) {
            const v = await openDefaultVolume(gpu.device, {});
            const iso = await Isosurface.create(gpu, v.stream, { memoryBudgetBytes: BUDGET / 2 });
            for (let j = 0; j < 5; j++) await iso.compute(0.2 + 0.15 * j);
            iso.destroy();
            v.stream.destroy();
          } else {
            const t = await openStream(gpu, k % 3 === 0 ? neghip : hydrogen);
            for (let j = 0; j < 8; j++) await t.c.setIsovalue(k % 3 === 0 ? 20 + 25 * j : 5 + 30 * j);
            expect(t.errors).toEqual([]);
            expect(t.fetcher.counters.cacheBytes).toBeLessThanOrEqual(CPU_CACHE);
            t.c.destroy();
          }
          expect(count.live).toBe(base);
        }
        expect(over).toBe(0);
      } finally {
        count.restore();
      }
    },
    900_000,
  );

  gpuTest(
    'refined by the view: camera moves landing while chunks arrive and surfaces compute, isovalues, at every allocation within the budget; every byte back',
    async ({ gpu }) => {
      (await openDefaultVolume(gpu.device, {})).stream.destroy();
      const count = countBuffers(gpu.device);
      const base = count.live;
      // a budget that binds: the cut is made coarser, the copies drawn of each step (snapshots) included
      const budget = 6 * MiB;
      let over = 0;
      count.onAllocate = (live) => {
        if (live - base > budget) over = Math.max(over, live - base);
      };
      try {
        const store = await openStore(storeForLocation(hydrogen), hydrogen);
        const fetcher = new ChunkFetcher(store, { maxInFlight: 4, cacheBytes: CPU_CACHE });
        const stream = await StoreStream.byView(store, fetcher, chunkedGpu(gpu), budget);
        const errors: string[] = [];
        stream.onError((e) => errors.push(e.message));
        let bound = 0;
        let shows = 0;
        stream.onShown((shown) => {
          shows++;
          if (shown.cut?.limitedByBudget) bound++;
        });
        const stops: string[] = [];
        stream.onProgress((p) => {
          if (p.phase === 'stopped') stops.push(`${p.level}: ${p.reason}`);
        });
        const radius = sceneRadiusOf(fitBox0(store.levels[0].layout, 0), store.voxelSize);
        const view = (box: [number, number, number, number, number, number]) => ({
          camera: cameraFromView(cameraForBox(box, store.voxelSize, DEFAULT_VIEWPORT).state, DEFAULT_VIEWPORT, radius),
          tolerancePx: 1.5,
        });
        const boxes: [number, number, number, number, number, number][] = [
          [0, 0, 0, 127, 127, 127],
          [64, 64, 64, 127, 127, 127],
          [0, 0, 0, 40, 40, 40],
          [40, 40, 40, 90, 90, 90],
          [0, 64, 0, 63, 127, 63],
        ];
        await stream.setView(view(boxes[0]));
        await stream.setIsovalue(20);
        // each move lands 0-250 ms into the previous refinement (fetching or computing), newest wins
        const random = mulberry32(11);
        const runs: Promise<unknown>[] = [];
        for (let i = 0; i < 12; i++) {
          runs.push(i % 4 === 3 ? stream.setIsovalue(10 + 60 * random()) : stream.setView(view(boxes[i % boxes.length])));
          await new Promise((r) => setTimeout(r, 250 * random()));
        }
        await Promise.all(runs);
        expect(errors).toEqual([]);
        expect(stream.shown?.final).toBe(true);
        console.log(
          `view stream at ${budget / MiB} MiB: ${shows} steps shown, ${bound} of them cut short by the budget; stops: ${stops.join('; ') || 'none'}`,
        );
        // the budget binds: some steps were made coarser for it
        expect(bound).toBeGreaterThan(0);
        stream.destroy();
        store.close?.();
        expect(count.live).toBe(base);
        expect(over).toBe(0);
      } finally {
        count.restore();
      }
    },
    900_000,
  );
});
