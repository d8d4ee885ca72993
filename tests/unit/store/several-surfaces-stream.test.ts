// Several surfaces of a store (issue 45): the stream draws every isovalue in
// each step from the same resident chunks. Checked on a CPU stand-in of the
// GPU side (pools, surfaces that count their computations and make copies,
// every byte through the budget's meter), against the store's own range
// arrays read with NumPy (zarr-python): the chunks a step draws are those
// any of its isovalues needs (the 27-neighbourhood rule written in NumPy
// here); the others are computed once each and copied; moving one isovalue
// recomputes only it while the step's chunks stay; a copy no step draws is
// let go; nothing is left on the meter. The real GPU side is held to the
// in-core surfaces by tests/unit/store/cli.test.ts (extract STORE --iso a,b).
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, it } from 'vitest';
import { GpuBudget } from '../../../src/gpu/budget.ts';
import { GpuMemoryMeter } from '../../../src/gpu/memory-meter.ts';
import { ChunkFetcher } from '../../../src/store/fetch/chunk-fetcher.ts';
import type { LevelStats, StreamGpu, SurfaceCopy } from '../../../src/store/stream-port.ts';
import { LevelPlanner } from '../../../src/store/stream/level-planner.ts';
import { StoreStream } from '../../../src/store/stream/store-stream.ts';
import { storeForLocation } from '../../../src/store/zarr/node-store.ts';
import { openStore, type ZfpStore } from '../../../src/store/zarr/open-store.ts';
import { FakePool } from './fake-pool.ts';
import { convert, converterPython } from './stores.ts';

const work = mkdtempSync(join(tmpdir(), 'several-surfaces-'));
const path = join(work, 'hydrogen.zarr');
/** Per isovalue (argv[2]: JSON list), the level-0 chunks (x fastest) whose 27-neighbourhood range holds it: NumPy over the store's range array. */
let neededByIso: Map<number, Set<number>>;
const ISOS = [5, 12, 20, 40, 60, 90];

beforeAll(() => {
  convert('volumes/hydrogen_atom_128x128x128_float32.raw', path, ['--chunk', '16', '--rate', '4', '--levels', '2']);
  const out = converterPython(
    `
import sys, json, zarr, numpy as np
g = zarr.open_group(sys.argv[1], mode='r')
r = np.asarray(g['ranges/0'][:], dtype=np.float32)     # z, y, x, 2
lo, hi = r[..., 0], r[..., 1]
def nb(a, f, fill):
    p = np.pad(a, 1, constant_values=fill)
    out = a.copy()
    for dz in range(3):
        for dy in range(3):
            for dx in range(3):
                out = f(out, p[dz:dz + a.shape[0], dy:dy + a.shape[1], dx:dx + a.shape[2]])
    return out
nlo, nhi = nb(lo, np.minimum, np.inf), nb(hi, np.maximum, -np.inf)
res = {}
for iso in json.loads(sys.argv[2]):
    v = np.float32(iso)
    res[str(iso)] = [int(i) for i in np.flatnonzero(((nlo < v) & (v <= nhi)).ravel())]
print(json.dumps(res))
`,
    [path, JSON.stringify(ISOS)],
  );
  neededByIso = new Map(Object.entries(JSON.parse(out) as Record<string, number[]>).map(([k, v]) => [Number(k), new Set(v)]));
}, 300_000);
afterAll(() => rmSync(work, { recursive: true, force: true }));

/** Bytes counted on a meter while held. */
function held(meter: GpuMemoryMeter, bytes: number) {
  meter.add(bytes);
  let live = true;
  return () => {
    if (live) meter.remove(bytes);
    live = false;
  };
}

/** The GPU side on the CPU: surfaces log what they compute (level, isovalue) and count their live copies. */
function fakePort(store: ZfpStore, parent: GpuMemoryMeter) {
  const meter = new GpuMemoryMeter(parent);
  const computed: [number, number][] = [];
  const copies = new Set<SurfaceCopy & { iso: number }>();
  const port: StreamGpu<FakePool, LevelStats & { drawn: number }> = {
    get allocatedBytes() {
      return meter.bytes;
    },
    poolBytesFor: (layout, n) => n * layout.chunkBytes,
    createVolume: (layout, n) => new FakePool(layout, n, meter),
    async createSurface(pool) {
      const level = store.levels.findIndex((l) => l.layout === pool.layout);
      const freeFixed = held(meter, 4096);
      let last = { iso: Number.NaN, drawn: 0 };
      let freeCopy = () => {};
      return {
        budgetedBytes: 0,
        get presentBytesNeeded() {
          return 100 * last.drawn + 64;
        },
        presentedBytes: 0,
        present() {
          freeCopy();
          freeCopy = held(meter, 100 * last.drawn + 64);
        },
        trimCache() {},
        setMemoryBudget() {},
        async compute(iso: number) {
          await new Promise((r) => setTimeout(r, 1));
          computed.push([level, iso]);
          last = { iso, drawn: pool.drawn?.size ?? 0 };
          return { triangles: last.drawn, cacheBytes: 0, vertexBytes: 0, drawn: last.drawn };
        },
        copy() {
          const bytes = 100 * last.drawn + 64;
          const free = held(meter, bytes);
          const c = {
            iso: last.iso,
            byteSize: bytes,
            destroy() {
              free();
              copies.delete(c);
            },
          };
          copies.add(c);
          return c;
        },
        destroy() {
          freeFixed();
          freeCopy();
        },
      };
    },
  };
  return { port, meter, computed, copies };
}

async function open(budget: GpuBudget) {
  const store = await openStore(storeForLocation(path), path);
  const fetcher = new ChunkFetcher(store, { maxInFlight: 4 });
  const fake = fakePort(store, budget.meter);
  const stream = await StoreStream.create(store, fetcher, fake.port, budget, new LevelPlanner(store.levels[0].layout));
  // level 0 only (the CLI's --level 0)
  stream.finest = 0;
  stream.coarsest = 0;
  // chunks fetched (not served from the CPU-side cache)
  const fetched: number[] = [];
  fetcher.onChunk((level, chunk, _bytes, fromCache) => {
    if (!fromCache) fetched.push(level * 2 ** 32 + chunk);
  });
  return { stream, fetched, ...fake };
}

const union = (...isos: number[]) => new Set(isos.flatMap((i) => [...neededByIso.get(i)!]));
const sorted = (s: Iterable<number>) => [...s].sort((a, b) => a - b);

describe('several surfaces of a store', () => {
  it('each step draws every isovalue from the chunks any of them needs; moving one recomputes only it while the chunks stay', async () => {
    const budget = new GpuBudget(64 << 20);
    const { stream, computed, copies, meter, fetched } = await open(budget);
    // isovalues whose chunks nest: the widest one's chunks hold the others'
    const bySize = [...ISOS].sort((a, b) => neededByIso.get(b)!.size - neededByIso.get(a)!.size);
    const wide = bySize[0];
    const inside = bySize.filter((i) => i !== wide && [...neededByIso.get(i)!].every((c) => neededByIso.get(wide)!.has(c)));
    expect(inside.length, 'two isovalues whose chunks lie within the widest one').toBeGreaterThanOrEqual(2);
    const [a, a2] = inside;
    // the fewest chunks of the rest: a step with it instead of the widest draws fewer chunks
    const narrow = [...bySize].reverse().find((i) => i !== a && i !== a2 && i !== wide)!;

    await stream.setIsovalue(a, [wide]);
    let shown = stream.shown!;
    expect(shown.iso).toBe(a);
    expect(shown.others).toEqual([wide]);
    expect(sorted(shown.levels[0].drawn)).toEqual(sorted(union(a, wide)));
    // fetched once: the chunks either needs, no more
    expect(sorted(fetched)).toEqual(sorted(union(a, wide)));
    // the other first, copied; the step's own isovalue last
    expect(computed).toEqual([
      [0, wide],
      [0, a],
    ]);
    expect([...copies].map((c) => c.iso)).toEqual([wide]);
    const wideCopy = shown.levels[0].others[0].copy;

    // the selected surface moves within the same chunks: only it is computed; the other's copy is kept
    await stream.setIsovalue(a2, [wide]);
    shown = stream.shown!;
    expect(shown.iso).toBe(a2);
    expect(computed.slice(2)).toEqual([[0, a2]]);
    expect(shown.levels[0].others[0].copy).toBe(wideCopy);
    expect(fetched.length).toBe(union(a, wide).size);

    // another other: the chunks change, the old copy goes once the new step shows
    await stream.setIsovalue(a2, [narrow]);
    shown = stream.shown!;
    expect(sorted(shown.levels[0].drawn)).toEqual(sorted(union(a2, narrow)));
    expect(union(a2, narrow).size).toBeLessThan(union(a2, wide).size);
    expect([...copies].map((c) => c.iso)).toEqual([narrow]);

    // no others: no copies
    await stream.setIsovalue(a2, []);
    expect(stream.shown!.others).toEqual([]);
    expect(copies.size).toBe(0);
    // the default keeps the last call's others
    await stream.setIsovalue(a, [wide, a, wide]);
    expect(stream.shown!.others).toEqual([wide]);
    await stream.setIsovalue(a2);
    expect(stream.shown!.others).toEqual([wide]);

    stream.destroy();
    expect(copies.size).toBe(0);
    expect(meter.bytes).toBe(0);
    expect(budget.heldBytes).toBe(0);
  }, 120_000);
});
