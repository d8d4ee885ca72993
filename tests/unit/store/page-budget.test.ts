// A CPU model of the page's one GPU budget (src/gpu/budget.ts), as the page
// drives its stores (src/app/store/store-view.ts): every stream holds against
// one GpuBudget; the budget is lowered mid-refinement and raised; the page
// switches between two stores ten times (the one on screen suspends to the
// copies it draws, the next opens within what is left, the old one ends once
// the new one is drawn), a switch to a store that fails to open resumes the
// one on screen; then everything closes. The GPU side is a CPU stand-in whose
// pools and surfaces allocate through a child of the budget's meter (the
// real GpuMemoryMeter), so every allocation is checked against the limit in
// force when it is made, and every byte must come back. Truth from outside
// the streams: the meter's count and the stores' range arrays.
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, it } from 'vitest';
import { GpuBudget } from '../../../src/gpu/budget.ts';
import { GpuMemoryMeter } from '../../../src/gpu/memory-meter.ts';
import { ChunkFetcher } from '../../../src/store/fetch/chunk-fetcher.ts';
import { chunksNeeded, neighbourhoodRanges } from '../../../src/store/plan.ts';
import type { LevelStats, StreamGpu } from '../../../src/store/stream-port.ts';
import { LevelPlanner } from '../../../src/store/stream/level-planner.ts';
import { StoreStream } from '../../../src/store/stream/store-stream.ts';
import { cameraForBox, fitBox0 } from '../../../src/store/view/camera.ts';
import { DEFAULT_VIEWPORT } from '../../../src/store/view/view-request.ts';
import { storeForLocation } from '../../../src/store/zarr/node-store.ts';
import { openStore, type ZfpStore } from '../../../src/store/zarr/open-store.ts';
import { convert } from './stores.ts';
import { FakePool } from './fake-pool.ts';

const work = mkdtempSync(join(tmpdir(), 'page-budget-'));
const storeA = join(work, 'gen128.zarr');
const storeB = join(work, 'hydrogen.zarr');
const KiB = 1024;
/** The stream keeps 1 MiB of any budget free for short-lived buffers (stream-memory.ts): the budgets here are that and the room that binds. */
const HIGH = 5 * 1024 * KiB;
const LOW = 2 * 1024 * KiB;
const ISO_A = 0.437;
const ISO_B = 40;

beforeAll(() => {
  convert('gen:128x128x128', storeA, ['--chunk', '16', '--rate', '4', '--levels', '4']);
  convert('volumes/hydrogen_atom_128x128x128_float32.raw', storeB, ['--chunk', '16', '--rate', '4', '--levels', '4']);
}, 600_000);
afterAll(() => rmSync(work, { recursive: true, force: true }));

/** Bytes counted on a meter while held: `set` replaces what is held. */
class Held {
  #bytes = 0;
  constructor(readonly meter: GpuMemoryMeter) {}
  set(bytes: number): void {
    if (this.#bytes > 0) this.meter.remove(this.#bytes);
    this.#bytes = bytes;
    if (bytes > 0) this.meter.add(bytes);
  }
  get bytes(): number {
    return this.#bytes;
  }
}

interface FakeStats extends LevelStats {
  drawn: number;
}

/** Per drawn chunk that holds surface: a surface's cache and vertices, and its drawn copy. */
const SURFACE_PER_CHUNK = 12000;
const COPY_PER_CHUNK = 3000;

/**
 * A CPU stand-in for the GPU side, every byte through a child of `parent`:
 * pools; surfaces with per-level buffers (made with the surface), cache and
 * vertices (grown by compute within the surface's cap, refused over it as the
 * Isosurface refuses), and a drawn copy (present); release() keeps the copy
 * only, and a released surface computes nothing.
 */
function fakePort(store: ZfpStore, ranges: Float32Array[], parent: GpuMemoryMeter) {
  const meter = new GpuMemoryMeter(parent);
  const port: StreamGpu<FakePool, FakeStats> = {
    get allocatedBytes() {
      return meter.bytes;
    },
    poolBytesFor: (layout, n) => n * layout.chunkBytes,
    createVolume: (layout, n) => new FakePool(layout, n, meter),
    async createSurface(pool, cap0) {
      const level = store.levels.findIndex((l) => l.layout === pool.layout);
      const nb = neighbourhoodRanges(pool.layout.chunkGrid, ranges[level]);
      const fixed = new Held(meter);
      const work = new Held(meter);
      const copy = new Held(meter);
      fixed.set(2000 + 48 * pool.blocksPerChunk * pool.poolChunks);
      let cap = cap0;
      let released = false;
      let destroyed = false;
      let computed = 0;
      return {
        get budgetedBytes() {
          return work.bytes;
        },
        get presentedBytes() {
          return copy.bytes;
        },
        get presentBytesNeeded() {
          return 300 + COPY_PER_CHUNK * computed;
        },
        present() {
          if (!released) copy.set(300 + COPY_PER_CHUNK * computed);
        },
        trimCache() {},
        setMemoryBudget(bytes: number) {
          cap = bytes;
        },
        release() {
          released = true;
          fixed.set(0);
          work.set(0);
        },
        async compute(iso: number) {
          await new Promise((r) => setTimeout(r, 1));
          if (released || destroyed) throw new Error(`Isosurface: ${destroyed ? 'destroyed' : 'released to its drawn copy'}`);
          const needed = new Set(chunksNeeded(nb, iso));
          for (const c of [...(pool.drawn ?? []), ...pool.ghosts])
            if (needed.has(c) && !pool.has(c)) throw new Error(`level ${level}: chunk ${c} computed while absent`);
          const drawn = [...(pool.drawn ?? pool.resident)].filter((c) => needed.has(c)).length;
          const need = SURFACE_PER_CHUNK * drawn;
          if (need > cap)
            throw Object.assign(new Error(`level ${level}: the surface needs ${need} B, the budget is ${cap} B`), {
              name: 'IsosurfaceBudgetError',
              neededBytes: need,
              budgetBytes: cap,
            });
          work.set(need);
          computed = drawn;
          return { triangles: drawn, cacheBytes: need / 2, vertexBytes: need / 2, drawn };
        },
        destroy() {
          destroyed = true;
          fixed.set(0);
          work.set(0);
          copy.set(0);
        },
      };
    },
  };
  return { port, meter };
}

/** A store opened the way the page opens it: its own fetcher and port, the page's budget; by the view (A) or level by level (B). */
async function open(path: string, budget: GpuBudget) {
  const store = await openStore(storeForLocation(path), path);
  const ranges = await Promise.all(store.levels.map((_, i) => store.readRanges(i).then((r) => r!)));
  const fetcher = new ChunkFetcher(store, { maxInFlight: 4 });
  const { port, meter } = fakePort(store, ranges, budget.meter);
  const byView = path === storeA;
  const stream = byView
    ? await StoreStream.byView(store, fetcher, port, budget)
    : await StoreStream.create(store, fetcher, port, budget, new LevelPlanner(store.levels[0].layout));
  if (byView)
    await stream.setView({
      camera: cameraForBox(fitBox0(store.levels[0].layout, 0), store.voxelSize, DEFAULT_VIEWPORT),
      tolerancePx: 0.75,
    });
  const errors: string[] = [];
  stream.onError((e) => errors.push(e.message));
  return { store, stream, meter, errors, iso: byView ? ISO_A : ISO_B };
}

describe("the page's one budget", () => {
  it('across a lower and a higher budget, ten store switches, a failed open and closes: every allocation within the budget, every byte back', async () => {
    const budget = new GpuBudget(HIGH);
    let over = 0;
    budget.meter.onAllocate = (bytes) => {
      if (bytes > budget.bytes) over = Math.max(over, bytes - budget.bytes);
    };

    // a store on screen at a budget that binds
    const a = await open(storeA, budget);
    await a.stream.setIsovalue(a.iso);
    expect(a.stream.shown?.levels.length).toBeGreaterThan(0);
    const drawnBefore = a.stream.shown!.levels.reduce((n, l) => n + l.drawn.length, 0);

    // lowered while a new isovalue refines: within the new limit at once (before anything else runs), still drawn
    const refining = a.stream.setIsovalue(a.iso * 1.1);
    await new Promise((r) => setTimeout(r, 3));
    budget.bytes = LOW;
    expect(budget.heldBytes).toBeLessThanOrEqual(LOW);
    // the step on screen alone held more: it keeps only the copies it is drawn from until a coarser one replaces it
    expect(a.stream.shown?.frozen).toBe(true);
    expect(a.stream.gpuBytes.pools).toBe(0);
    await refining;
    // a coarser step replaced the copies on screen (refining further may stop for the budget, and say so)
    const stops: string[] = [];
    a.stream.onProgress((p) => {
      if (p.phase === 'stopped') stops.push(`${p.cause}`);
    });
    await a.stream.setIsovalue(a.iso);
    expect(stops.filter((c) => c !== 'budget')).toEqual([]);
    expect(budget.heldBytes).toBeLessThanOrEqual(LOW);
    expect(a.stream.shown?.frozen).toBeFalsy();
    expect(a.stream.shown?.levels.length).toBeGreaterThan(0);
    const drawnLow = a.stream.shown!.levels.reduce((n, l) => n + l.drawn.length, 0);
    expect(drawnLow).toBeLessThan(drawnBefore);

    // raised: the refinement goes finer again
    budget.bytes = HIGH;
    await a.stream.setIsovalue(a.iso);
    expect(a.stream.shown!.levels.reduce((n, l) => n + l.drawn.length, 0)).toBeGreaterThan(drawnLow);

    // ten switches, A <-> B: the one on screen keeps only its copies while the next opens; the old ends once the new shows
    const after: number[] = [];
    let current = a;
    for (let k = 0; k < 10; k++) {
      current.stream.suspend();
      expect(current.stream.gpuBytes.pools).toBe(0);
      const copies = current.meter.bytes;
      expect(copies).toBeGreaterThan(0);
      const next = await open(k % 2 === 0 ? storeB : storeA, budget);
      await next.stream.setIsovalue(next.iso);
      expect(next.stream.shown?.levels.length, `switch ${k + 1}`).toBeGreaterThan(0);
      // nothing of the suspended store moved meanwhile
      expect(current.meter.bytes).toBe(copies);
      current.stream.destroy();
      expect(current.meter.bytes).toBe(0);
      expect(current.errors).toEqual([]);
      current = next;
      after.push(budget.heldBytes);
    }
    // no switch leaves anything behind: the same store at the same isovalue holds the same each time
    for (let k = 2; k < 10; k++) expect(after[k], `switch ${k + 1}`).toBe(after[k - 2]);

    // a store that fails to open: the one on screen was suspended, and goes on (a step at its isovalue, not the copies)
    current.stream.suspend();
    await expect(open(join(work, 'missing.zarr'), budget)).rejects.toThrow();
    await current.stream.setIsovalue(current.iso);
    expect(current.stream.suspended).toBe(false);
    expect(current.stream.shown?.frozen).toBeFalsy();
    expect(current.stream.shown?.iso).toBe(current.iso);
    expect(current.errors).toEqual([]);

    current.stream.destroy();
    expect(budget.heldBytes).toBe(0);
    expect(over).toBe(0);
  }, 300_000);

  it('level by level too: a lower budget freezes the level on screen to its copies at once, then a coarser level replaces it', async () => {
    const budget = new GpuBudget(HIGH);
    let over = 0;
    budget.meter.onAllocate = (bytes) => {
      if (bytes > budget.bytes) over = Math.max(over, bytes - budget.bytes);
    };
    const s = await open(storeB, budget);
    await s.stream.setIsovalue(s.iso);
    const fine = s.stream.shown!.levels[0].level;
    budget.bytes = LOW;
    expect(budget.heldBytes).toBeLessThanOrEqual(LOW);
    expect(s.stream.shown?.frozen).toBe(true);
    await s.stream.setIsovalue(s.iso);
    expect(s.stream.shown?.frozen).toBeFalsy();
    expect(s.stream.shown!.levels[0].level).toBeGreaterThan(fine);
    expect(budget.heldBytes).toBeLessThanOrEqual(LOW);
    s.stream.destroy();
    expect(budget.heldBytes).toBe(0);
    expect(over).toBe(0);
  }, 120_000);

  it('a budget below the copies on screen: they go too (listeners hear an empty step), then a coarse step within it', async () => {
    const budget = new GpuBudget(HIGH);
    let over = 0;
    budget.meter.onAllocate = (bytes) => {
      if (bytes > budget.bytes) over = Math.max(over, bytes - budget.bytes);
    };
    const s = await open(storeA, budget);
    await s.stream.setIsovalue(s.iso);
    const shown: number[] = [];
    s.stream.onShown((step) => shown.push(step.levels.length));
    // 1 MiB kept free for staging, and less than the copies of the step on screen hold (the stand-in's triangles are its drawn chunks)
    const copies = s.stream.shown!.levels.reduce((a, l) => a + 300 + COPY_PER_CHUNK * l.stats.triangles, 0);
    const tiny = 1024 * KiB + copies - 1;
    expect(copies).toBeGreaterThan(400 * KiB); // room for a coarse step once they are gone
    budget.bytes = tiny;
    expect(budget.heldBytes).toBeLessThanOrEqual(tiny);
    expect(shown).toEqual([0]);
    expect(s.stream.shown?.levels).toEqual([]);
    await s.stream.setIsovalue(s.iso);
    expect(s.stream.shown?.levels.length).toBeGreaterThan(0);
    expect(budget.heldBytes).toBeLessThanOrEqual(tiny);
    s.stream.destroy();
    expect(budget.heldBytes).toBe(0);
    expect(over).toBe(0);
  }, 120_000);

  it('a suspended stream runs nothing: no fetch, no timer, no step, whatever arrives', async () => {
    const budget = new GpuBudget(HIGH);
    const s = await open(storeB, budget);
    // the first isovalue is fetching when the stream is suspended
    const run = s.stream.setIsovalue(s.iso);
    await new Promise((r) => setTimeout(r, 2));
    let shows = 0;
    s.stream.onShown(() => shows++);
    s.stream.suspend();
    await run;
    const fetcher = s.stream.fetcher;
    await fetcher.idle();
    const requests = fetcher.counters.requests;
    await new Promise((r) => setTimeout(r, 200));
    expect(fetcher.counters.requests).toBe(requests);
    expect(fetcher.counters.inFlight).toBe(0);
    expect(shows).toBe(0);
    // a budget change does not wake it
    budget.bytes = 2 * HIGH;
    await new Promise((r) => setTimeout(r, 50));
    expect(fetcher.counters.requests).toBe(requests);
    expect(shows).toBe(0);
    s.stream.destroy();
    expect(budget.heldBytes).toBe(0);
  }, 120_000);
});
