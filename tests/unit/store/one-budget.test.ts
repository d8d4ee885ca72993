// One budget, spent where needed. The bonsai at two low isovalues (2-3
// million triangles: the in-core pipeline needs 130-150 MB of cache and
// vertices, more than the quarter of 512 MB the old split gave a store's
// surface) from a store of 64^3 chunks (8 MB of chunks in all): the GPU
// bytes the store path holds at its peak, counted by a wrapper around
// createBuffer/destroy, are at most 10% above the in-core path's for the
// same surfaces (level 0 as one stream, byte-equal to zfpy's); the store
// fits a budget of 300 MB where in-core fits --cache-budget 256 (and not
// 128); the record's gpuBytes equals what the wrapper counted; closing
// frees every byte.
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect } from 'vitest';
import { Isosurface } from '../../../src/isosurface/isosurface.ts';
import { IsosurfaceBudgetError } from '../../../src/isosurface/types.ts';
import { assembleLevelStream } from '../../../src/store/assemble.ts';
import { openStoreInput } from '../../../src/store/cli-input.ts';
import { storeForLocation } from '../../../src/store/zarr/node-store.ts';
import { openStore } from '../../../src/store/zarr/open-store.ts';
import { loadZfpStream } from '../../../src/zfp/gpu-stream.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { countBuffers } from '../../helpers/gpu-memory.ts';
import { convert } from './stores.ts';

const work = mkdtempSync(join(tmpdir(), 'store-budget-'));
const path = join(work, 'bonsai.zarr');
const MiB = 2 ** 20;
const ISOS = [10, 20];

beforeAll(() => {
  convert('volumes/bonsai_256x256x256_float32.rate4.zfp', path, ['--chunk', '64', '--rate', '4']);
}, 900_000);
afterAll(() => rmSync(work, { recursive: true, force: true }));

describe('one budget for a store and in-core', () => {
  gpuTest(
    'a store level holds at most 10% more than in-core for the same surfaces; 300 MB fits; gpuBytes = the wrapper',
    async ({ gpu }) => {
      const store = await openStore(storeForLocation(path), path);
      const L = store.levels[0];
      const chunks = await Promise.all(Array.from({ length: L.chunkCount }, (_, i) => store.readChunk(0, i)));
      const whole = assembleLevelStream(L.layout, (c) => chunks[c]);
      const count = countBuffers(gpu.device);
      try {
        // in-core, --cache-budget 128: the surfaces do not fit (the old store split gave a surface 128 of 512 MB)
        {
          const stream = loadZfpStream(gpu.device, whole, 'bonsai level 0');
          const iso = await Isosurface.create(gpu, stream, { memoryBudgetBytes: 128 * MiB });
          await expect(iso.compute(ISOS[0])).rejects.toBeInstanceOf(IsosurfaceBudgetError);
          iso.destroy();
          stream.destroy();
        }
        // in-core, --cache-budget 256: they fit
        const before = count.live;
        count.resetPeak();
        const stream = loadZfpStream(gpu.device, whole, 'bonsai level 0');
        const iso = await Isosurface.create(gpu, stream, { memoryBudgetBytes: 256 * MiB });
        const inCore: number[] = [];
        for (const v of ISOS) inCore.push((await iso.compute(v)).triangles);
        const inCorePeak = count.peak - before;
        iso.destroy();
        stream.destroy();
        expect(count.live).toBe(before);
        expect(inCore[0]).toBeGreaterThan(2_000_000);

        // the store at level 0 within 300 MB for everything
        count.resetPeak();
        const input = await openStoreInput(gpu, path, { level: 0, budget: 300 * MiB });
        const streamed: number[] = [];
        for (const v of ISOS) {
          streamed.push((await input.surface.compute(v)).triangles);
          const r = input.record();
          expect(r.gpuBytes).toBe(count.live - before);
          expect(r.gpuBytes).toBeLessThanOrEqual(300 * MiB);
        }
        const storePeak = count.peak - before;
        expect(streamed).toEqual(inCore);
        const r = input.record();
        expect(r.gpuPoolBytes).toBeLessThan(1.01 * L.storedBytes + MiB); // the pool holds the chunks the surfaces need, no more
        expect(r.gpuPeakBytes).toBe(storePeak);
        console.log(
          `peak GPU bytes: in-core ${(inCorePeak / MiB).toFixed(1)} MiB, store ${(storePeak / MiB).toFixed(1)} MiB (pool ${(r.gpuPoolBytes / MiB).toFixed(1)}, cache ${(r.gpuCacheBytes / MiB).toFixed(1)}, vertices ${(r.gpuVertexBytes / MiB).toFixed(1)})`,
        );
        expect(storePeak).toBeLessThanOrEqual(1.1 * inCorePeak);
        input.surface.destroy();
        expect(count.live).toBe(before);
      } finally {
        count.restore();
      }
    },
    600_000,
  );
});
