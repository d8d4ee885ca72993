// The stream controller's decisions, on real converted stores through the
// real fetcher, with a CPU stand-in for the GPU side (pool = a set of
// resident chunks, checked for capacity; a surface that fails unless every
// chunk its isovalue needs is resident). The GPU path itself is tested in
// the CLI tests once ChunkedVolume exists.
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, it } from 'vitest';
import { ChunkFetcher } from '../../../src/store/fetch/chunk-fetcher.ts';
import { chunksNeeded, neighbourhoodRanges } from '../../../src/store/plan.ts';
import { estimateFixedBytes } from '../../../src/store/level-state.ts';
import { LevelStream } from '../../../src/store/stream/level-stream.ts';
import type { RoleVolume } from '../../../src/store/stream/stream-types.ts';
import type { LevelStats, StreamGpu, StreamProgress } from '../../../src/store/stream-port.ts';
import type { ChunkLevelLayout } from '../../../src/store/types.ts';
import { storeForLocation } from '../../../src/store/zarr/node-store.ts';
import { openStore, type ZfpStore } from '../../../src/store/zarr/open-store.ts';
import { convert } from './stores.ts';

const work = mkdtempSync(join(tmpdir(), 'store-stream-'));
const path = join(work, 'hydrogen.zarr');

class FakeVolume implements RoleVolume {
  resident = new Set<number>();
  destroyed = false;
  constructor(
    readonly layout: ChunkLevelLayout,
    public poolChunks: number,
  ) {}
  get poolBytes() {
    return fakePoolBytes(this.layout, this.poolChunks);
  }
  get residentCount() {
    return this.resident.size;
  }
  get freeCount() {
    return this.poolChunks - this.resident.size;
  }
  has(c: number) {
    return this.resident.has(c);
  }
  put(c: number, bytes: Uint8Array) {
    if (bytes.length !== this.layout.chunkBytes) throw new Error('wrong size');
    if (this.resident.size >= this.poolChunks) throw new Error(`${this.layout.name}: pool full`);
    this.resident.add(c);
  }
  evict(c: number) {
    this.resident.delete(c);
  }
  resize(n: number) {
    if (n < this.resident.size) throw new Error('shrinks below the resident chunks');
    this.poolChunks = n;
  }
  slotOfChunk() {
    return undefined;
  }
  reserve() {}
  setRoles() {}
  isReserved() {
    return false;
  }
  readonly blocksPerChunk = 64;
  destroy() {
    this.destroyed = true;
  }
}

const fakePoolBytes = (layout: ChunkLevelLayout, n: number) => n * layout.chunkBytes + 4 * layout.chunkGrid.reduce((a, b) => a * b);
/** A fake surface's per-level buffers and its cache + vertices. */
const SURFACE_FIXED = 1000;
const SURFACE_BUDGETED = 2000;

function fakeGpu(store: ZfpStore, ranges: Float32Array[]) {
  const volumes: FakeVolume[] = [];
  const surfaces = new Set<{ destroyed: boolean }>();
  const gpu: StreamGpu<FakeVolume, LevelStats> = {
    get allocatedBytes() {
      let n = 0;
      for (const v of volumes) if (!v.destroyed) n += v.poolBytes;
      return n + surfaces.size * (SURFACE_FIXED + SURFACE_BUDGETED);
    },
    poolBytesFor: fakePoolBytes,
    createVolume: (layout, pool) => {
      const v = new FakeVolume(layout, pool);
      volumes.push(v);
      return v;
    },
    async createSurface(volume) {
      const level = store.levels.findIndex((l) => l.layout === volume.layout);
      const nb = neighbourhoodRanges(volume.layout.chunkGrid, ranges[level]);
      const me = { destroyed: false };
      surfaces.add(me);
      let cap = Infinity;
      return {
        budgetedBytes: SURFACE_BUDGETED,
        trimCache() {},
        setMemoryBudget(bytes: number) {
          cap = bytes;
        },
        async compute(iso: number) {
          const need = chunksNeeded(nb, iso);
          const absent = need.filter((c) => !volume.has(c));
          if (absent.length) throw new Error(`computed with ${absent.length} needed chunks absent`);
          if (cap < SURFACE_BUDGETED) throw Object.assign(new Error('over the cap'), { name: 'IsosurfaceBudgetError' });
          return { triangles: need.length, cacheBytes: 1000, vertexBytes: 1000 };
        },
        destroy() {
          surfaces.delete(me);
        },
      };
    },
  };
  return { gpu, volumes };
}

async function setup(budget: number, maxInFlight = 8) {
  const store = await openStore(storeForLocation(path), path);
  const ranges = await Promise.all(store.levels.map((_, i) => store.readRanges(i).then((r) => r!)));
  const fetcher = new ChunkFetcher(store, { maxInFlight });
  const { gpu, volumes } = fakeGpu(store, ranges);
  const c = await LevelStream.create(store, fetcher, gpu, budget);
  const progress: StreamProgress[] = [];
  const shown: Array<[number, number]> = [];
  c.onProgress((p) => progress.push(p));
  c.onShown((s) => shown.push([s.level, s.iso]));
  return { store, ranges, fetcher, c, progress, shown, volumes };
}

beforeAll(() => {
  convert('volumes/hydrogen_atom_128x128x128_float32.raw', path, ['--chunk', '16', '--rate', '6', '--levels', '4']);
}, 900_000);
afterAll(() => rmSync(work, { recursive: true, force: true }));

describe('LevelStream', () => {
  it('shows the coarsest level first, then refines to level 0, fetching only needed chunks', async () => {
    const { store, ranges, fetcher, c, progress, shown } = await setup(256 << 20);
    await c.setIsovalue(20);
    expect(shown.map(([l]) => l)).toEqual([3, 2, 1, 0]);
    const needed = store.levels.map((l, i) => chunksNeeded(neighbourhoodRanges(l.layout.chunkGrid, ranges[i]), 20).length);
    const chunkBytes = store.levels.map((l) => l.layout.chunkBytes);
    const bound = needed.reduce((a, n, i) => a + n * chunkBytes[i], 0);
    expect(fetcher.counters.bytesFetched).toBe(bound); // exactly the needed chunks, once
    expect(progress.filter((p) => p.phase === 'shown').map((p) => [p.level, p.chunksDone, p.chunksNeeded])).toEqual(
      needed.map((n, i) => [i, n, n]).reverse(),
    );
    // scrubbing back to the same value: all resident, level 0 at once, nothing fetched
    const before = fetcher.counters.requests;
    await c.setIsovalue(20);
    expect(shown.at(-1)).toEqual([0, 20]);
    expect(fetcher.counters.requests).toBe(before);
    c.destroy();
  });

  it('fast scrubbing aborts stale requests; the last value ends at level 0 like a fresh open', async () => {
    const { fetcher, c, shown } = await setup(256 << 20, 2);
    // scrub while level 0's chunks are on their way; nearest-first from a
    // corner, whose chunks the later (higher) isovalues do not need
    c.focus = [0, 0, 0];
    const fetchingLevel0 = new Promise<void>((r) =>
      c.onProgress((p) => {
        if (p.level === 0 && p.phase === 'fetching') r();
      }),
    );
    const runs = [c.setIsovalue(1)];
    await fetchingLevel0;
    runs.push(...[200, 2, 150, 4, 100, 8, 5].map((iso) => c.setIsovalue(iso)));
    await Promise.all(runs);
    expect(fetcher.counters.aborted).toBeGreaterThan(0);
    expect(shown.at(-1)).toEqual([0, 5]);
    expect(c.shown!.stats.triangles).toBeGreaterThan(0);
    const fresh = await setup(256 << 20);
    fresh.c.focus = [0, 0, 0];
    await fresh.c.setIsovalue(5);
    expect(fresh.c.shown!.stats).toEqual(c.shown!.stats);
    c.destroy();
    fresh.c.destroy();
  });

  it('within a budget smaller than the store: stops at the finest level that fits, says why, never above budget', async () => {
    const { store, c, progress, shown, fetcher } = await setup(0);
    const storeBytes = store.levels.reduce((a, l) => a + l.storedBytes, 0);
    // 1 MiB kept for staging: level 0's per-level buffers (about 1.6 MiB) and pool at low isovalues do not fit the other 2
    const budget = 3 << 20;
    expect(store.levels[0].storedBytes + estimateFixedBytes(store.levels[0].layout, store.levels[0].chunkCount)).toBeGreaterThan(
      budget - (1 << 20),
    );
    expect(storeBytes).toBeGreaterThan(0);
    const small = await setup(budget);
    for (let i = 0; i < 20; i++) {
      await small.c.setIsovalue(0.5 + i * 7);
      expect(small.c.gpuBytes.total).toBeLessThanOrEqual(budget);
      expect(small.c.shown).not.toBeNull();
    }
    const stops = small.progress.filter((p) => p.phase === 'stopped');
    expect(stops.length).toBeGreaterThan(0);
    expect(stops[0].reason).toMatch(/level \d( needs \d+ chunks|'s surface needs about)/);
    // budget 0: nothing fits, nothing fetched, the reason is given
    await c.setIsovalue(10);
    expect(shown).toEqual([]);
    expect(fetcher.counters.requests).toBe(0);
    expect(progress.at(-1)!.reason).toMatch(/level 3 needs \d+ chunks .* the budget of 0\.0 MiB has 0\.0 MiB free/);
    small.c.destroy();
  });

  it('a level it cannot draw stops with its limit named; a range array that holds nothing makes every chunk needed; neither hangs', async () => {
    const { store, c, progress, shown } = await setup(256 << 20);
    // level 3 pinned, and it cannot be drawn: a stop naming the limit, nothing shown
    c.finest = 3;
    c.coarsest = 3;
    store.levels[3].unusable = 'level 3 is wider than a surface can be';
    await c.setIsovalue(20);
    expect(shown).toEqual([]);
    expect(progress.at(-1)).toMatchObject({ phase: 'stopped', cause: 'limit', reason: 'level 3 is wider than a surface can be' });
    store.levels[3].unusable = null;
    // level 2, whose range array reads as none: every chunk needed (the plan does not wait for it again)
    store.readRanges = async () => null;
    c.finest = 2;
    c.coarsest = 2;
    await c.setIsovalue(20);
    expect(shown.at(-1)).toEqual([2, 20]);
    const shownProgress = progress.filter((p) => p.phase === 'shown').at(-1)!;
    expect(shownProgress.chunksNeeded).toBe(store.levels[2].chunkCount);
    c.destroy();
  });
});
