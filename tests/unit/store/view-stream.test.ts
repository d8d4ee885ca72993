// The view stream's decisions (src/store/stream/store-stream.ts), on a real
// converted store through the real fetcher, with a CPU stand-in for the GPU
// (a pool is a set of resident chunks with their roles; a surface that
// fails unless every drawn chunk and ghost the isovalue needs is resident).
// Truth from outside the stream: the cut module's own rule (view-cut.test.ts
// checks it against a brute-force reference) and the store's range arrays.
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, it } from 'vitest';
import { ChunkFetcher } from '../../../src/store/fetch/chunk-fetcher.ts';
import { chunksNeeded, neighbourhoodRanges } from '../../../src/store/plan.ts';
import type { LevelStats, StreamGpu } from '../../../src/store/stream-port.ts';
import type { ChunkIndex } from '../../../src/store/types.ts';
import { cameraForBox, cameraFromView, fitBox0, sceneRadiusOf } from '../../../src/store/view/camera.ts';
import { DEFAULT_VIEWPORT } from '../../../src/store/view/view-request.ts';
import { type ShownCut, StoreStream } from '../../../src/store/stream/store-stream.ts';
import { storeForLocation } from '../../../src/store/zarr/node-store.ts';
import { openStore, type ZfpStore } from '../../../src/store/zarr/open-store.ts';
import { SimulatedLinkStore } from '../../../src/store/zarr/stores.ts';
import { convert } from './stores.ts';
import { FakePool } from './fake-pool.ts';

const work = mkdtempSync(join(tmpdir(), 'view-stream-'));
const path = join(work, 'gen128.zarr');
const ISO = 0.437;
beforeAll(() => {
  convert('gen:128x128x128', path, ['--chunk', '16', '--rate', '4', '--levels', '4']);
}, 600_000);
afterAll(() => rmSync(work, { recursive: true, force: true }));

interface FakeStats extends LevelStats {
  drawn: number;
}

/**
 * `bytesPerDrawn`: a surface's cache and vertices take this much per drawn
 * chunk (a dense surface); over its cap (setMemoryBudget) it refuses as the
 * Isosurface does, with what it needs.
 */
/** What a fake surface computed last, and the copy of it present() made (what the page draws). */
interface FakeDrawn {
  iso: number;
  drawn: number[];
}

/**
 * `cacheOnly`: the rays' surfaces: a cache that grows takes up to half its
 * need again as headroom where its cap has room (as the Isosurface's does),
 * and reports what it needed without it unless `hideNeeded`.
 */
function fakeGpu(store: ZfpStore, ranges: Float32Array[], bytesPerDrawn = 0, cacheOnly?: { hideNeeded: boolean }) {
  const pools: FakePool[] = [];
  /** Called at the start of every compute (a test moves the camera from here). */
  const hooks: { onCompute?: () => void } = {};
  const surfaces = new Map<object, { held: number; copy: number }>();
  let peak = 0;
  const gpu: StreamGpu<FakePool, FakeStats> = {
    get allocatedBytes() {
      let n = 0;
      for (const p of pools) if (!p.destroyed) n += p.poolBytes;
      for (const s of surfaces.values()) n += 4000 + s.held + s.copy;
      peak = Math.max(peak, n);
      return n;
    },
    poolBytesFor: (layout, n) => n * layout.chunkBytes,
    ...(cacheOnly ? { cacheOnly: true } : {}),
    createVolume: (layout, n) => {
      const p = new FakePool(layout, n);
      pools.push(p);
      return p;
    },
    async createSurface(pool) {
      const level = store.levels.findIndex((l) => l.layout === pool.layout);
      const nb = neighbourhoodRanges(pool.layout.chunkGrid, ranges[level]);
      const me = {};
      const state = { held: 0, cap: Infinity, copy: 0 };
      surfaces.set(me, state);
      let computed: FakeDrawn | null = null;
      let presented: FakeDrawn | null = null;
      return {
        get budgetedBytes() {
          return 2000 + state.held;
        },
        get computed() {
          return computed;
        },
        get presented() {
          return presented;
        },
        present() {
          presented = computed && { iso: computed.iso, drawn: [...computed.drawn] };
          state.copy = 300;
        },
        get presentedBytes() {
          return state.copy;
        },
        presentBytesNeeded: 300,
        // a cache-only surface holds nothing but its cache
        trimCache() {
          if (cacheOnly) state.held = 0;
        },
        setMemoryBudget(bytes: number) {
          state.cap = bytes;
        },
        async compute(iso: number) {
          hooks.onCompute?.();
          await new Promise((r) => setTimeout(r, 1));
          const needed = new Set(chunksNeeded(nb, iso));
          // every drawn chunk and ghost the surface needs is resident: the drawn chunks' cells are complete
          for (const c of [...(pool.drawn ?? []), ...pool.ghosts])
            if (needed.has(c) && !pool.has(c)) throw new Error(`level ${level}: chunk ${c} computed while absent`);
          const drawn = pool.drawn === null ? pool.resident.size : [...pool.drawn].filter((c) => needed.has(c)).length;
          const need = 2000 + bytesPerDrawn * drawn;
          if (need > state.cap)
            throw Object.assign(new Error(`level ${level}: the surface needs ${need} B, the budget is ${state.cap} B`), {
              name: 'IsosurfaceBudgetError',
              neededBytes: need,
              budgetBytes: state.cap,
            });
          const headroom = cacheOnly ? Math.max(0, Math.min(0.5 * (need - 2000), state.cap - need)) : 0;
          state.held = need - 2000 + headroom;
          computed = { iso, drawn: [...(pool.drawn ?? pool.resident)].sort((a, b) => a - b) };
          const reported = cacheOnly && !cacheOnly.hideNeeded ? { cacheBytesNeeded: 1000 + need - 2000 } : {};
          return { triangles: 0, cacheBytes: 1000 + state.held, ...reported, vertexBytes: 1000, drawn: pool.drawn?.size ?? 0 };
        },
        destroy() {
          surfaces.delete(me);
        },
      };
    },
  };
  return { gpu, pools, peak: () => peak, hooks };
}

async function setup(
  budget = 2 ** 30,
  link?: { mbitPerSecond: number; latencyMs: number },
  bytesPerDrawn = 0,
  cacheOnly?: { hideNeeded: boolean },
) {
  const files = storeForLocation(path);
  const store = await openStore(link ? new SimulatedLinkStore(files, link) : files, path);
  const ranges = await Promise.all(store.levels.map((_, i) => store.readRanges(i).then((r) => r!)));
  const fetcher = new ChunkFetcher(store, { maxInFlight: 4 });
  const fake = fakeGpu(store, ranges, bytesPerDrawn, cacheOnly);
  const stream = await StoreStream.byView(store, fetcher, fake.gpu, budget);
  const shown: ShownCut<FakePool, FakeStats, unknown>[] = [];
  stream.onShown((s) => shown.push(s as ShownCut<FakePool, FakeStats, unknown>));
  const sceneRadius = sceneRadiusOf(fitBox0(store.levels[0].layout, 0), store.voxelSize);
  const view = (box: [number, number, number, number, number, number], tolerancePx = 1.5) => ({
    camera: cameraFromView(cameraForBox(box, store.voxelSize, DEFAULT_VIEWPORT).state, DEFAULT_VIEWPORT, sceneRadius),
    tolerancePx,
  });
  return { store, ranges, fetcher, stream, shown, fake, view };
}

/** Level-0 voxels covered by the leaves of a step, each counted per leaf. */
function coverage(store: ZfpStore, leaves: ChunkIndex[][]): Uint8Array {
  const d = store.levels[0].layout.dims;
  const out = new Uint8Array(d[0] * d[1] * d[2]);
  leaves.forEach((chunks, L) => {
    const { chunkEdge, chunkGrid: g } = store.levels[L].layout;
    const e = chunkEdge * 2 ** L;
    for (const c of chunks) {
      const x0 = (c % g[0]) * e;
      const y0 = (Math.floor(c / g[0]) % g[1]) * e;
      const z0 = Math.floor(c / (g[0] * g[1])) * e;
      for (let z = z0; z < Math.min(z0 + e, d[2]); z++)
        for (let y = y0; y < Math.min(y0 + e, d[1]); y++)
          for (let x = x0; x < Math.min(x0 + e, d[0]); x++) out[x + d[0] * (y + d[1] * z)]++;
    }
  });
  return out;
}

describe('StoreStream', () => {
  it('coarse to fine: each step covers every voxel once, ends at the cut, and draws and ghosts every needed chunk resident', async () => {
    const { store, stream, shown, view } = await setup();
    await stream.setView(view([100, 100, 100, 127, 127, 127]));
    await stream.setIsovalue(ISO);
    expect(shown.length).toBeGreaterThan(1);
    const finest = shown.map((s) => s.step);
    // steps go from the coarsest level used to the finest, one level at a time
    expect(finest).toEqual([...finest].sort((a, b) => b - a));
    for (const s of shown) expect(coverage(store, s.leaves).every((n) => n === 1)).toBe(true);
    const last = shown.at(-1)!;
    expect(last.final).toBe(true);
    // the final step is the cut itself
    last.cut!.levels.forEach((l, L) => expect(new Set(last.leaves[L])).toEqual(new Set(l.drawn)));
    expect(last.levels.some((l) => l.level === 0)).toBe(true);
    stream.destroy();
  });

  it("two camera moves in a row: newest wins, both refinements end, the last cut shown is the second view's", async () => {
    const { stream, shown, view } = await setup();
    await stream.setView(view([0, 0, 0, 127, 127, 127], 6));
    await stream.setIsovalue(ISO);
    const first = stream.setView(view([100, 100, 100, 127, 127, 127]));
    const second = stream.setView(view([0, 0, 0, 27, 27, 27]));
    await Promise.all([first, second]);
    const last = shown.at(-1)!;
    expect(last.final).toBe(true);
    // the last step shown is the second view's cut
    const again = await setup();
    await again.stream.setView(again.view([0, 0, 0, 27, 27, 27]));
    await again.stream.setIsovalue(ISO);
    const ref = again.shown.at(-1)!;
    last.cut!.levels.forEach((l, L) => expect(new Set(l.drawn)).toEqual(new Set(ref.cut!.levels[L].drawn)));
    stream.destroy();
    again.stream.destroy();
  });

  it('steps are snapshots: while surfaces compute and camera moves supersede them, every level drawn is a copy of the step shown, whole', async () => {
    const { stream, shown, view, fake } = await setup();
    type Drawable = { presented: FakeDrawn | null; computed: FakeDrawn | null };
    let checks = 0;
    let stale = 0;
    /** What the page draws (each shown level's copy) is the shown step: its isovalue and its drawn chunks, every level. */
    const drawnIsShown = () => {
      const s = stream.shown;
      if (!s) return;
      checks++;
      for (const l of s.levels) {
        const surface = l.surface as unknown as Drawable;
        expect(surface.presented, `level ${l.level}`).toEqual({ iso: s.iso, drawn: [...l.drawn].sort((a, b) => a - b) });
        // the surface itself has moved on (computed in place for a newer step) while its copy is drawn
        if (surface.computed && JSON.stringify(surface.computed) !== JSON.stringify(surface.presented)) stale++;
      }
    };
    stream.onShown(() => drawnIsShown());
    await stream.setView(view([0, 0, 0, 127, 127, 127], 6));
    await stream.setIsovalue(ISO);
    // camera moves and an isovalue change land while surfaces compute (from inside a computation) and while chunks are in flight
    const moves = [
      view([100, 100, 100, 127, 127, 127]),
      view([0, 0, 0, 27, 27, 27]),
      view([0, 0, 0, 127, 127, 127], 3),
      view([60, 0, 0, 127, 60, 60]),
    ];
    const pending: Promise<unknown>[] = [];
    let computes = 0;
    fake.hooks.onCompute = () => {
      drawnIsShown();
      computes++;
      if (computes % 3 === 0 && moves.length > 0) pending.push(stream.setView(moves.shift()!));
      if (computes === 7) pending.push(stream.setIsovalue(ISO * 1.3));
    };
    pending.push(stream.setView(view([0, 0, 0, 63, 63, 63])));
    while (pending.length > 0) await pending.shift();
    fake.hooks.onCompute = undefined;
    drawnIsShown();
    expect(shown.at(-1)!.final).toBe(true);
    expect(checks).toBeGreaterThanOrEqual(8);
    // some copies were drawn while their surfaces had already moved on: the case the copies are for
    expect(stale).toBeGreaterThan(0);
    stream.destroy();
  });

  it('a camera move that leaves the cut as it is shows nothing again (no fetch, no surface computed)', async () => {
    const { stream, shown, fetcher, view } = await setup();
    await stream.setView(view([100, 100, 100, 127, 127, 127]));
    await stream.setIsovalue(ISO);
    const steps = shown.length;
    const requests = fetcher.counters.requests;
    await stream.setView(view([100, 100, 100, 127, 127, 127]));
    expect(shown.length).toBe(steps);
    expect(fetcher.counters.requests).toBe(requests);
    // a new isovalue is computed again
    await stream.setIsovalue(ISO + 0.1);
    expect(shown.length).toBeGreaterThan(steps);
    stream.destroy();
  });

  it('an isovalue no chunk holds: an empty final step is shown (nothing drawn, no error), and the next isovalue draws again', async () => {
    const { stream, shown, view, ranges } = await setup();
    const errors: Error[] = [];
    stream.onError((e) => errors.push(e));
    await stream.setView(view([0, 0, 0, 127, 127, 127], 6));
    await stream.setIsovalue(ISO);
    expect(shown.at(-1)!.levels.length).toBeGreaterThan(0);
    // below every chunk's range (the store's own range arrays say so)
    let lo = Infinity;
    for (const r of ranges) for (let i = 0; i < r.length; i += 2) lo = Math.min(lo, r[i]);
    await stream.setIsovalue(lo - 1);
    const empty = shown.at(-1)!;
    expect(empty.iso).toBe(lo - 1);
    expect(empty.final).toBe(true);
    expect(empty.levels).toEqual([]);
    expect(coverage(stream.store, empty.leaves).every((n) => n === 1)).toBe(true);
    await stream.setIsovalue(ISO);
    expect(shown.at(-1)!.levels.length).toBeGreaterThan(0);
    expect(errors).toEqual([]);
    stream.destroy();
  });

  it('a camera move back to the cut on screen while a finer step is fetching: its requests are aborted, none stays in flight', async () => {
    // a slow link: the zoomed view's chunks are still on their way when the camera goes back
    const { stream, shown, fetcher, view } = await setup(2 ** 30, { mbitPerSecond: 20, latencyMs: 60 });
    await stream.setView(view([0, 0, 0, 127, 127, 127], 6));
    await stream.setIsovalue(ISO);
    const steps = shown.length;
    const zooming = stream.setView(view([100, 100, 100, 127, 127, 127]));
    while (fetcher.counters.inFlight === 0) await new Promise((r) => setTimeout(r, 5));
    const aborted = fetcher.counters.aborted;
    await stream.setView(view([0, 0, 0, 127, 127, 127], 6));
    await zooming;
    expect(fetcher.counters.aborted).toBeGreaterThan(aborted);
    expect(fetcher.counters.inFlight).toBe(0);
    // the coarse cut stayed on screen, whole
    const last = shown.at(-1)!;
    expect(last.final).toBe(true);
    expect(coverage(stream.store, last.leaves).every((n) => n === 1)).toBe(true);
    expect(shown.length).toBeGreaterThanOrEqual(steps);
    stream.destroy();
  });

  it('within the budget: GPU bytes never exceed it, the cut says the budget binds', async () => {
    const budget = 1536 << 10;
    const { stream, shown, fake, view } = await setup(budget);
    const stops: string[] = [];
    stream.onProgress((p) => {
      if (p.phase === 'stopped') stops.push(p.reason ?? '');
    });
    await stream.setView(view([100, 100, 100, 127, 127, 127]));
    await stream.setIsovalue(ISO);
    expect(fake.peak()).toBeLessThanOrEqual(budget);
    expect(stops).toEqual([]);
    expect(shown.at(-1)!.cut!.limitedByBudget).toBe(true);
    stream.destroy();
  });

  it("a refinement the stream wants on its own (a new budget) goes to its owner's refineAgain when set (the page's bookkeeping), else it refines itself", async () => {
    for (const owned of [false, true]) {
      const { stream, shown, view } = await setup(1536 << 10);
      await stream.setView(view([100, 100, 100, 127, 127, 127]));
      await stream.setIsovalue(ISO);
      const before = shown.length;
      let asked = 0;
      if (owned)
        stream.refineAgain = () => {
          asked++;
          void stream.setIsovalue(ISO);
        };
      let refined = 0;
      stream.onProgress((p) => {
        if (p.phase === 'shown') refined++;
      });
      stream.budget.bytes = 4 << 20;
      await new Promise((r) => setTimeout(r, 300));
      await stream.setIsovalue(ISO);
      expect(asked).toBe(owned ? 1 : 0);
      expect(refined).toBeGreaterThan(0);
      expect(shown.length).toBeGreaterThan(before);
      stream.destroy();
    }
  });

  it('a cut the budget held back, whose surfaces took far less than first guessed, is planned again with what they took: finer, within the budget', async () => {
    // the stand-in's surfaces take a few KiB, far under the first guess (half of each chunk's blocks active)
    const budget = 1536 << 10;
    const { stream, shown, fake, view } = await setup(budget);
    await stream.setView(view([100, 100, 100, 127, 127, 127]));
    await stream.setIsovalue(ISO);
    // each plan's last step is shown whole (final); the second plan's draws more of level 0 than the first's
    const finals = shown.filter((s) => s.final);
    expect(finals.length).toBeGreaterThanOrEqual(2);
    const last = shown.at(-1)!;
    expect(last).toBe(finals.at(-1));
    const level0 = (s: (typeof shown)[number]) => s.cut!.levels[0].drawn.length;
    expect(level0(last)).toBeGreaterThan(level0(finals[0]));
    expect(coverage(stream.store, last.leaves).every((n) => n === 1)).toBe(true);
    expect(fake.peak()).toBeLessThanOrEqual(budget);
    stream.destroy();
  });
});

describe('StoreStream within a budget its surfaces outgrow', () => {
  // A dense surface: 400 KiB of cache and vertices per drawn chunk, far above the cut's first guess, so the
  // cut planned from chunk bytes does not fit and must be made coarser once the surfaces' size is known.
  const DENSE = 400 << 10;
  it('a cut whose surfaces do not fit is made coarser until it fits: shown whole, never over the budget, no stop', async () => {
    const free = await setup(2 ** 30, undefined, DENSE);
    await free.stream.setView(free.view([0, 0, 0, 127, 127, 127]));
    await free.stream.setIsovalue(ISO);
    const unlimited = free.shown.at(-1)!;
    const finestFree = Math.min(...unlimited.levels.map((l) => l.level));
    expect(finestFree).toBe(0);
    free.stream.destroy();

    const budget = 6 << 20;
    const { stream, shown, fake, view } = await setup(budget, undefined, DENSE);
    const stops: string[] = [];
    stream.onProgress((p) => {
      if (p.phase === 'stopped') stops.push(p.reason ?? '');
    });
    await stream.setView(view([0, 0, 0, 127, 127, 127]));
    await stream.setIsovalue(ISO);
    const last = shown.at(-1)!;
    expect(last.final, 'the whole (coarser) cut is shown').toBe(true);
    expect(stops).toEqual([]);
    expect(coverage(stream.store, last.leaves).every((n) => n === 1)).toBe(true);
    // coarser than the cut an unlimited budget gives, and within the budget at every moment
    const drawnAt = (c: typeof last, L: number) => c.levels.find((l) => l.level === L)?.drawn.length ?? 0;
    expect(drawnAt(last, 0)).toBeLessThan(drawnAt(unlimited, 0));
    expect(fake.peak()).toBeLessThanOrEqual(budget);
    // another isovalue and a camera move keep to it
    await stream.setIsovalue(ISO + 0.05);
    await stream.setView(view([100, 100, 100, 127, 127, 127]));
    expect(shown.at(-1)!.final).toBe(true);
    expect(stops).toEqual([]);
    expect(fake.peak()).toBeLessThanOrEqual(budget);
    stream.destroy();
  });

  it('a cache-only surface (rays) whose cache took headroom where the budget had room: the plan counts what its blocks need, not the headroom, so the cut is finer, within the budget', async () => {
    const budget = 6 << 20;
    const cut = async (hideNeeded: boolean) => {
      const { stream, shown, fake, view } = await setup(budget, undefined, 40 << 10, { hideNeeded });
      const stops: string[] = [];
      stream.onProgress((p) => {
        if (p.phase === 'stopped') stops.push(p.reason ?? '');
      });
      await stream.setView(view([0, 0, 0, 127, 127, 127]));
      await stream.setIsovalue(ISO);
      const last = shown.at(-1)!;
      stream.destroy();
      return { last, stops, peak: fake.peak() };
    };
    const counted = await cut(true);
    const needed = await cut(false);
    for (const r of [counted, needed]) {
      expect(r.last.final).toBe(true);
      expect(r.stops).toEqual([]);
      expect(r.peak).toBeLessThanOrEqual(budget);
    }
    const finer = (c: typeof counted.last) => c.cut!.levels.reduce((a, l, L) => a + l.drawn.length * 8 ** (3 - L), 0);
    expect(finer(needed.last)).toBeGreaterThan(finer(counted.last));
  });

  it('a coarser plan whose last step is already on screen (shown on the way, not final) ends the refinement: listeners hear it as final', async () => {
    // dense enough that level 1 never fits: the plans coarsen until the last is the level-2 step shown on the way
    const { stream, shown, view } = await setup(6 << 20, undefined, 200 << 10, { hideNeeded: true });
    const phases: string[] = [];
    stream.onProgress((p) => phases.push(p.phase));
    await stream.setView(view([0, 0, 0, 127, 127, 127]));
    await stream.setIsovalue(ISO);
    const last = shown.at(-1)!;
    expect(last.final).toBe(true);
    expect(stream.shown).toBe(last);
    expect(phases.at(-1)).toBe('shown');
    expect(phases).not.toContain('stopped');
    // the refinement did end on a step shown before (the case this is about)
    expect(shown.filter((s) => s.step === last.step).length).toBeGreaterThan(1);
    stream.destroy();
  });

  it('a budget the coarsest level alone does not fit: the refinement stops and says so', async () => {
    const { stream, view } = await setup(3 << 20, undefined, 4 << 20);
    const stops: { reason?: string; cause?: string }[] = [];
    stream.onProgress((p) => {
      if (p.phase === 'stopped') stops.push(p);
    });
    await stream.setView(view([0, 0, 0, 127, 127, 127]));
    await stream.setIsovalue(ISO);
    expect(stops.length).toBe(1);
    expect(stops[0].cause).toBe('budget');
    expect(stops[0].reason).toMatch(/the surface needs \d+ B, the budget is/);
    stream.destroy();
  });
});

describe('StoreStream over a level wider than 16384 voxels', () => {
  // gen:16400x8x8 in 16^3 chunks: level 0 is 16400 voxels wide (past 16384, where vertices once ran out of bits), level 1 is 8200
  const wide = join(work, 'wide.zarr');
  beforeAll(() => {
    convert('gen:16400x8x8', wide, ['--chunk', '16', '--rate', '2']);
  }, 600_000);

  it('zoomed into its far end, the cut reaches level 0 there, and every camera move ends', async () => {
    const store = await openStore(storeForLocation(wide), wide);
    expect(store.levels.every((l) => !l.unusable)).toBe(true);
    expect(store.notes.join(' ')).not.toMatch(/cannot be shown/);
    const ranges = await Promise.all(store.levels.map((_, i) => store.readRanges(i).then((r) => r!)));
    const stream = await StoreStream.byView(store, new ChunkFetcher(store, { maxInFlight: 4 }), fakeGpu(store, ranges).gpu, 2 ** 30);
    const shown: ShownCut<FakePool, FakeStats, unknown>[] = [];
    stream.onShown((s) => shown.push(s as ShownCut<FakePool, FakeStats, unknown>));
    const sceneRadius = sceneRadiusOf(fitBox0(store.levels[0].layout, 0), store.voxelSize);
    let [lo, hi] = [Infinity, -Infinity];
    for (let i = 0; i < ranges[1].length; i += 2) [lo, hi] = [Math.min(lo, ranges[1][i]), Math.max(hi, ranges[1][i + 1])];
    // the whole volume, then ever closer to its far end (where the page's wheel took the tab down)
    for (const x0 of [0, 8192, 15000, 16300, 16380]) {
      const box: [number, number, number, number, number, number] = [x0, 0, 0, 16399, 7, 7];
      const camera = cameraFromView(cameraForBox(box, store.voxelSize, DEFAULT_VIEWPORT).state, DEFAULT_VIEWPORT, sceneRadius);
      const done = stream.setView({ camera, tolerancePx: 1.5 });
      if (x0 === 0) await stream.setIsovalue((lo + hi) / 2);
      await Promise.race([
        done,
        new Promise((_, reject) => setTimeout(() => reject(new Error(`the view at x0 = ${x0} did not end`)), 30_000)),
      ]);
      expect(shown.at(-1)!.final).toBe(true);
    }
    // zoomed in on the far end, level 0 is drawn where the camera looks
    expect(shown.at(-1)!.levels.some((l) => l.level === 0)).toBe(true);
    stream.destroy();
  });
});
