// Chunk roles in a GPU chunk pool (ChunkedVolume.setRoles): a level's surface
// drawn only in some chunks ('drawn'), other resident chunks lending their
// voxels to them ('ghost'), also drawing their layer of cells next to a drawn
// chunk ('skirt') or unused ('idle'). The reference is the same
// pool with every chunk drawn, which chunked-volume.test.ts checks against
// the in-core pipeline. Stores are written by our converter (numcodecs zfpy,
// fixed rate) from volumes whose edge chunks are partial (66^3 in 16^3
// chunks, 68^3 in 32^3 chunks). Triangles are compared as their three
// vertices' position words (edge and fraction; block coordinates), exact;
// a triangle's cell is the lowest of its vertices' edge ends (no
// marching-cubes triangle lies in a cell's upper face).
import { mulberry32 } from '../../../src/util/random.ts';
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, test } from 'vitest';
import { Isosurface } from '../../../src/isosurface/isosurface.ts';
import type { IsosurfaceOptions } from '../../../src/isosurface/types.ts';
import { CHUNK_ROLE_CODES, type ChunkIndex, ChunkedVolume, type ChunkLevelLayout } from '../../../src/zfp/chunked-volume.ts';
import { codePathRerun, gpuTest } from '../../helpers/gpu.ts';
import { readCacheState, readVertices } from '../../helpers/isosurface-readback.ts';
import { convert } from './stores.ts';

const work = mkdtempSync(join(tmpdir(), 'chunk-roles-'));
afterAll(() => rmSync(work, { recursive: true, force: true }));

interface Case {
  key: string;
  input: string;
  dims: [number, number, number];
  chunk: number;
  rate: number;
  isovalues: number[];
}

const allCases: Case[] = [
  // 5^3 chunks, the last of 2 voxels along each axis (a partial block)
  { key: 'neghip', input: 'volumes/neghip_66x66x66_uint8.raw', dims: [66, 66, 66], chunk: 16, rate: 4, isovalues: [40.37, 133.37] },
  // 3^3 chunks, the last of 4 voxels along each axis
  { key: 'ironProt', input: 'volumes/ironProt_68x68x68_uint8.raw', dims: [68, 68, 68], chunk: 32, rate: 6, isovalues: [20.37, 90.37] },
];
// The suites that rerun this file for another code path (default limits, the GPU kernels) take the
// neghip pool (partial blocks at the edges) at one isovalue: the roles' logic is data-independent
// and the unit suite has run both pools at both isovalues.
const cases: Case[] = codePathRerun ? [{ ...allCases[0], isovalues: allCases[0].isovalues.slice(0, 1) }] : allCases;

const layouts = new Map<string, { store: string; layout: ChunkLevelLayout }>();

beforeAll(() => {
  for (const c of cases) {
    const store = convert(c.input, join(work, `${c.key}.zarr`), ['--chunk', String(c.chunk), '--rate', String(c.rate), '--levels', '1']);
    const first = readFileSync(join(store, '0', 'c', '0', '0', '0'));
    const chunkGrid = c.dims.map((n) => Math.ceil(n / c.chunk)) as [number, number, number];
    layouts.set(c.key, {
      store,
      layout: { dims: c.dims, chunkEdge: c.chunk, chunkGrid, rate: c.rate, chunkBytes: first.byteLength, name: `${c.key}.zarr level 0` },
    });
  }
}, 900_000);

/** Helpers over one level: chunk bytes, coordinates, neighbours. */
function level(key: string) {
  const { store, layout } = layouts.get(key)!;
  const [gx, gy, gz] = layout.chunkGrid;
  const count = gx * gy * gz;
  const coords = (chunk: ChunkIndex) => [chunk % gx, Math.floor(chunk / gx) % gy, Math.floor(chunk / (gx * gy))];
  const bytes = (chunk: ChunkIndex) => {
    const [x, y, z] = coords(chunk);
    return new Uint8Array(readFileSync(join(store, '0', 'c', String(z), String(y), String(x))));
  };
  /** The chunks a drawn set needs as ghosts: its +x/+y/+z and diagonal neighbours, not drawn. */
  const ghostsOf = (drawn: ReadonlySet<ChunkIndex>) => {
    const out = new Set<ChunkIndex>();
    for (const d of drawn) {
      const [x, y, z] = coords(d);
      for (let k = 1; k < 8; k++) {
        const [u, v, w] = [x + (k & 1), y + ((k >> 1) & 1), z + (k >> 2)];
        if (u >= gx || v >= gy || w >= gz) continue;
        const n = u + gx * (v + gy * w);
        if (!drawn.has(n)) out.add(n);
      }
    }
    return out;
  };
  const all = Array.from({ length: count }, (_, i) => i);
  /** Chunk index steps of the axes x, y, z. */
  const steps = [1, gx, gx * gy];
  return { layout, count, all, coords, bytes, ghostsOf, steps };
}

/** A pool of `capacity` slots holding `chunks` (in this order). */
function poolOf(gpu: { device: GPUDevice }, key: string, chunks: Iterable<ChunkIndex>, capacity?: number): ChunkedVolume {
  const L = level(key);
  const list = [...chunks];
  const pool = ChunkedVolume.create(gpu, L.layout, { poolChunks: capacity ?? Math.max(1, list.length) });
  for (const c of list) pool.put(c, L.bytes(c));
  return pool;
}

/** The surface's triangles: per triangle its key (the 6 position words), the chunk holding its cell's lowest corner, and that corner. */
interface Triangles {
  keys: string[];
  chunks: ChunkIndex[];
  cells: number[][];
}

async function trianglesOf(surface: Isosurface, layout: ChunkLevelLayout): Promise<Triangles> {
  const words = await readVertices(surface);
  const C = layout.chunkEdge;
  const [gx, gy] = layout.chunkGrid;
  const keys: string[] = [];
  const chunks: ChunkIndex[] = [];
  const cells: number[][] = [];
  for (let t = 0; 6 * t < words.length; t++) {
    const w = words.subarray(6 * t, 6 * t + 6);
    keys.push(w.join(','));
    // the cell: per axis the lowest lower end of the three vertices' edges (4 * block + corner)
    const low = [Infinity, Infinity, Infinity];
    for (let k = 0; k < 3; k++) {
      const w0 = w[2 * k];
      const w1 = w[2 * k + 1];
      const block = [w1 & 4095, (w1 >>> 12) & 4095, (w1 >>> 24) | (((w0 >>> 27) & 15) << 8)];
      const corner = [w0 & 7, (w0 >>> 3) & 7, (w0 >>> 6) & 7];
      for (let a = 0; a < 3; a++) low[a] = Math.min(low[a], 4 * block[a] + corner[a]);
    }
    const [cx, cy, cz] = low.map((g) => Math.floor(g / C));
    chunks.push(cx + gx * (cy + gy * cz));
    cells.push(low);
  }
  return { keys, chunks, cells };
}

/** The triangles of `all` whose cell lies in `chunks`, as sorted keys. */
function partOf(all: Triangles, chunks: ReadonlySet<ChunkIndex>): string[] {
  return all.keys.filter((_, i) => chunks.has(all.chunks[i])).sort();
}

const sorted = (t: Triangles) => [...t.keys].sort();

/**
 * The triangles of `all` that skirts make: those whose cell lies in a chunk G
 * of `skirts` at chunk-local coordinate 0 on an axis a whose G - e_a is in
 * `drawn`, as sorted keys.
 */
function skirtPartOf(
  all: Triangles,
  L: ReturnType<typeof level>,
  drawn: ReadonlySet<ChunkIndex>,
  skirts: ReadonlySet<ChunkIndex>,
): string[] {
  const C = L.layout.chunkEdge;
  return all.keys
    .filter((_, i) => {
      const g = all.chunks[i];
      if (!skirts.has(g)) return false;
      const cc = L.coords(g);
      return [0, 1, 2].some((a) => all.cells[i][a] % C === 0 && cc[a] > 0 && drawn.has(g - L.steps[a]));
    })
    .sort();
}

/** The chunks of `chunks` with a drawn chunk below them on some axis. */
function nextToDrawn(L: ReturnType<typeof level>, drawn: ReadonlySet<ChunkIndex>, chunks: Iterable<ChunkIndex>): Set<ChunkIndex> {
  return new Set([...chunks].filter((g) => [0, 1, 2].some((a) => L.coords(g)[a] > 0 && drawn.has(g - L.steps[a]))));
}

/** The same "random" sets every run. */
const random = mulberry32;

/** The mesh's position words and indices (the normals may follow the cache's history: left out). */
async function meshBytes(surface: Isosurface): Promise<{ positions: Uint32Array; indices: Uint32Array }> {
  const mesh = await surface.readMesh();
  const n = mesh.vertices.length / 3;
  const positions = new Uint32Array(2 * n);
  for (let v = 0; v < n; v++) {
    positions[2 * v] = mesh.vertices[3 * v];
    positions[2 * v + 1] = mesh.vertices[3 * v + 1];
  }
  return { positions, indices: mesh.indices };
}

const none = new Set<ChunkIndex>();

describe('chunk roles in a GPU chunk pool: drawn, ghost, idle', () => {
  test('the slot-table codes of the roles are the kernels’ (common.wgsl ROLE_*)', () => {
    const wgsl = readFileSync(new URL('../../../shaders/isosurface/common.wgsl', import.meta.url), 'utf8');
    for (const [role, code] of Object.entries(CHUNK_ROLE_CODES))
      expect(wgsl, role).toMatch(new RegExp(`^const ROLE_${role.toUpperCase()}: u32 = ${code}u;`, 'm'));
  });

  // One index shard; or shards of 97 triangles with the output growing from one triangle, so that
  // cells without indices fall on shard boundaries and the cell list overflows alone (all ghosts).
  const outputs: Array<[string, IsosurfaceOptions]> = [
    ['one index shard', {}],
    ['index shards of 97 triangles, growing', { maxVertexBindingBytes: 12 * 97, initialVertexCapacity: 3 }],
  ];
  for (const [c, [output, options]] of cases.flatMap((c) => outputs.map((o) => [c, o] as const))) {
    gpuTest(
      `${c.key} (${c.dims.join('x')} in ${c.chunk}^3 chunks, ${output}): a set drawn with the rest as ghosts and its complement split the all-drawn surface; awkward sets; setRoles(null) restores it`,
      async ({ gpu }) => {
        const L = level(c.key);
        const pool = poolOf(gpu, c.key, L.all);
        const surface = await Isosurface.create(gpu, pool, options);
        const rnd = random(27);
        for (const iso of c.isovalues) {
          const at = `${c.key} iso ${iso}`;
          pool.setRoles(null, none);
          const allStats = await surface.compute(iso);
          const all = await trianglesOf(surface, L.layout);
          const allMesh = await meshBytes(surface);
          expect(allStats.triangles, at).toBeGreaterThan(500);
          expect(all.keys.length).toBe(allStats.triangles);
          expect(new Set(all.keys).size, `${at}: every triangle once`).toBe(all.keys.length);
          const chunksWithTriangles = new Set(all.chunks);
          expect(chunksWithTriangles.size, at).toBeGreaterThan(3);

          // S drawn, every other chunk a ghost; then the complement drawn, S the ghosts
          const S = new Set(L.all.filter(() => rnd() < 0.4));
          const rest = new Set(L.all.filter((k) => !S.has(k)));
          pool.setRoles(S, rest);
          expect(L.all.map((k) => pool.roleOf(k))).toEqual(L.all.map((k) => (S.has(k) ? 'drawn' : 'ghost')));
          const sStats = await surface.compute(iso);
          const inS = await trianglesOf(surface, L.layout);
          pool.setRoles(rest, S);
          const cStats = await surface.compute(iso);
          const inRest = await trianglesOf(surface, L.layout);
          expect(inS.keys.length, at).toBeGreaterThan(0);
          expect(inRest.keys.length, at).toBeGreaterThan(0);
          expect(
            inS.chunks.every((k) => S.has(k)),
            `${at}: every triangle of the S surface in a cell of S`,
          ).toBe(true);
          expect(
            inRest.chunks.every((k) => rest.has(k)),
            `${at}: every triangle of the complement's surface in a cell of it`,
          ).toBe(true);
          const sKeys = new Set(inS.keys);
          expect(
            inRest.keys.some((k) => sKeys.has(k)),
            `${at}: the two surfaces share no triangle`,
          ).toBe(false);
          expect([...inS.keys, ...inRest.keys].sort(), `${at}: together the all-drawn surface`).toEqual(sorted(all));
          expect(sStats.triangles + cStats.triangles).toBe(allStats.triangles);
          // ghost blocks stay active by the usual rule; their vertices count, their triangles do not
          expect(sStats.activeBlocks).toBe(allStats.activeBlocks);
          const usedByS = new Set(
            inS.keys.flatMap((k) => {
              const w = k.split(',');
              return [0, 2, 4].map((j) => `${w[j]},${w[j + 1]}`);
            }),
          );
          expect(sStats.vertices, `${at}: the welded vertices include those the S triangles use`).toBeGreaterThanOrEqual(usedByS.size);

          // a single drawn chunk (the one with the most triangles), the rest ghosts
          const counts = new Map<ChunkIndex, number>();
          for (const k of all.chunks) counts.set(k, (counts.get(k) ?? 0) + 1);
          const busiest = [...counts.entries()].reduce((a, b) => (b[1] > a[1] ? b : a))[0];
          for (const one of [busiest, L.count - 1]) {
            // (L.count - 1: the chunk at the volume's upper corner, partial along every axis)
            const drawn = new Set([one]);
            pool.setRoles(drawn, new Set(L.all.filter((k) => k !== one)));
            await surface.compute(iso);
            expect(sorted(await trianglesOf(surface, L.layout)), `${at}: chunk ${one} alone drawn`).toEqual(partOf(all, drawn));
          }

          // every chunk a ghost: no triangle, the same active blocks, the lower faces' vertices
          pool.setRoles(none, new Set(L.all));
          const ghosts = await surface.compute(iso);
          expect(ghosts.triangles, `${at}: all ghosts`).toBe(0);
          expect(ghosts.indices).toBe(0);
          expect(ghosts.occupiedBlocks).toBe(0);
          expect(ghosts.activeBlocks).toBe(allStats.activeBlocks);
          expect(ghosts.vertices, `${at}: ghost-owned vertices on the chunks' lower faces`).toBeGreaterThan(0);
          expect((await surface.readMesh()).indices.length).toBe(0);
          // a new surface whose first is all ghosts: its cell list overflows while its indices (none) fit, and grows
          const fresh = await Isosurface.create(gpu, pool, { ...options, initialVertexCapacity: 3 });
          const firstGhosts = await fresh.compute(iso);
          expect(firstGhosts.grew).toBe(true);
          expect(firstGhosts.triangles).toBe(0);
          expect(firstGhosts.vertices).toBe(ghosts.vertices);
          fresh.destroy();

          // every chunk idle: nothing active
          pool.setRoles(none, none);
          expect(L.all.every((k) => pool.roleOf(k) === 'idle')).toBe(true);
          const idle = await surface.compute(iso);
          expect(idle.triangles, `${at}: all idle`).toBe(0);
          expect(idle.activeBlocks, `${at}: all idle`).toBe(0);
          expect(idle.vertices).toBe(0);

          // S drawn with just the ghosts it needs, the rest idle: the S part, and no idle chunk's block active
          const needed = L.ghostsOf(S);
          pool.setRoles(S, needed);
          const withIdle = await surface.compute(iso);
          expect(sorted(await trianglesOf(surface, L.layout)), `${at}: S with its ghosts, the rest idle`).toEqual(partOf(all, S));
          expect(withIdle.triangles).toBe(sStats.triangles);
          // this surface's active blocks: the last entries of the LRU log (each surface appends its active slots)
          const cache = await readCacheState(surface);
          expect(cache.lruOrder.length).toBeGreaterThanOrEqual(withIdle.activeBlocks);
          const ids = [...cache.lruOrder.subarray(cache.lruOrder.length - withIdle.activeBlocks)].map((slot) => cache.slotToBlock[slot]);
          const chunkInSlot = new Map(L.all.map((k) => [pool.slotOfChunk(k)!, k]));
          const activeChunks = new Set([...ids].map((b) => chunkInSlot.get(Math.floor(b / pool.blocksPerChunk))!));
          expect(
            [...activeChunks].filter((k) => pool.roleOf(k) === 'idle'),
            `${at}: active blocks of idle chunks`,
          ).toEqual([]);

          // S drawn, every other chunk idle: as if S alone were resident (no roles), whatever the block
          // cache still holds from the surfaces above. Cells whose edges' owners touch a missing chunk
          // make no triangle; every triangle made is one of the level's (no index names a vertex
          // nobody wrote: readMesh checks the range, the positions check the rest).
          pool.setRoles(S, none);
          await surface.compute(iso);
          const sIdle = sorted(await trianglesOf(surface, L.layout));
          const alone = poolOf(gpu, c.key, S);
          const aloneSurface = await Isosurface.create(gpu, alone, options);
          await aloneSurface.compute(iso);
          expect(sIdle, `${at}: S drawn, the rest idle = S alone in a pool`).toEqual(sorted(await trianglesOf(aloneSurface, L.layout)));
          const sPart = new Set(partOf(all, S));
          expect(
            sIdle.filter((k) => !sPart.has(k)),
            `${at}: S alone, triangles not in the level's surface`,
          ).toEqual([]);
          expect(sIdle.length, `${at}: S alone makes most of its triangles`).toBeGreaterThan(sPart.size / 3);
          aloneSurface.destroy();
          alone.destroy();

          // only S and its ghosts resident, the roles set before the chunks arrive: the S part
          const small = ChunkedVolume.create(gpu, L.layout, { poolChunks: S.size + needed.size });
          small.setRoles(S, needed);
          for (const k of [...needed, ...S]) small.put(k, L.bytes(k));
          const smallSurface = await Isosurface.create(gpu, small, options);
          await smallSurface.compute(iso);
          expect(sorted(await trianglesOf(smallSurface, L.layout)), `${at}: only S and its ghosts resident`).toEqual(partOf(all, S));
          smallSurface.destroy();
          small.destroy();

          // back to every chunk drawn: the same mesh, byte for byte
          pool.setRoles(null, S);
          expect(L.all.every((k) => pool.roleOf(k) === 'drawn')).toBe(true);
          const again = await surface.compute(iso);
          expect(again.triangles).toBe(allStats.triangles);
          expect(again.vertices).toBe(allStats.vertices);
          const againMesh = await meshBytes(surface);
          expect(Buffer.from(againMesh.positions.buffer).equals(Buffer.from(allMesh.positions.buffer)), `${at}: vertices`).toBe(true);
          expect(Buffer.from(againMesh.indices.buffer).equals(Buffer.from(allMesh.indices.buffer)), `${at}: indices`).toBe(true);
        }
        surface.destroy();
        pool.destroy();
      },
      900_000,
    );
  }

  // Skirts: every ghost a 'skirt', whose cells of chunk-local coordinate 0 on an axis whose chunk
  // below is drawn make the level's triangles of those cells; the drawn chunks' triangles unchanged.
  for (const [c, [output, options]] of cases.flatMap((c) => outputs.map((o) => [c, o] as const))) {
    gpuTest(
      `${c.key} (${c.dims.join('x')} in ${c.chunk}^3 chunks, ${output}): skirts add exactly the level's triangles of their layer next to a drawn chunk, the drawn part unchanged`,
      async ({ gpu }) => {
        const L = level(c.key);
        const pool = poolOf(gpu, c.key, L.all);
        const surface = await Isosurface.create(gpu, pool, options);
        const rnd = random(28);
        /** The surface with roles (drawn, skirts) and its checks: the drawn part, the skirts' part, the counts; its stats. */
        const check = async (at: string, drawn: Set<ChunkIndex>, skirts: Set<ChunkIndex>, all: Triangles, iso: number) => {
          pool.setRoles(drawn, skirts);
          const ghostStats = await surface.compute(iso);
          pool.setRoles(drawn, skirts, { skirts: true });
          for (const k of skirts) if (!drawn.has(k)) expect(pool.roleOf(k), `${at}: chunk ${k}`).toBe('skirt');
          for (const k of drawn) expect(pool.roleOf(k), `${at}: chunk ${k}`).toBe('drawn');
          const stats = await surface.compute(iso);
          // readMesh checks that no index points past the welded vertices
          const mesh = await surface.readMesh();
          expect(mesh.indices.length, at).toBe(3 * stats.triangles);
          const got = await trianglesOf(surface, L.layout);
          expect(got.keys.length).toBe(stats.triangles);
          expect(partOf(got, drawn), `${at}: the drawn chunks' triangles`).toEqual(partOf(all, drawn));
          const skirtPart = skirtPartOf(all, L, drawn, skirts);
          const outside = got.keys.filter((_, i) => !drawn.has(got.chunks[i])).sort();
          expect(outside, `${at}: the skirts' triangles = the level's of their layers next to a drawn chunk`).toEqual(skirtPart);
          // so a skirt with no drawn chunk below it makes none
          const lower = nextToDrawn(L, drawn, skirts);
          expect(
            got.chunks.filter((k) => skirts.has(k) && !lower.has(k)),
            `${at}: triangles of skirts with no drawn chunk below`,
          ).toEqual([]);
          expect(stats.triangles).toBe(ghostStats.triangles + skirtPart.length);
          expect(stats.vertices, `${at}: a skirt keeps at least a ghost's vertices`).toBeGreaterThanOrEqual(ghostStats.vertices);
          expect(stats.activeBlocks).toBe(ghostStats.activeBlocks);
          // per-block triangle counts (the cut's figures): per chunk, the triangles whose cell is in it, skirts included
          const { ids, triangles } = await surface.readBlockTriangles();
          const chunkInSlot = new Map(L.all.map((k) => [pool.slotOfChunk(k)!, k]));
          const perChunk = new Map<ChunkIndex, number>();
          for (let i = 0; i < ids.length; i++) {
            if (triangles[i] === 0) continue;
            const k = chunkInSlot.get(Math.floor(ids[i] / pool.blocksPerChunk))!;
            perChunk.set(k, (perChunk.get(k) ?? 0) + triangles[i]);
          }
          const expected = new Map<ChunkIndex, number>();
          for (const k of got.chunks) expected.set(k, (expected.get(k) ?? 0) + 1);
          expect(
            [...perChunk].sort((a, b) => a[0] - b[0]),
            `${at}: readBlockTriangles per chunk`,
          ).toEqual([...expected].sort((a, b) => a[0] - b[0]));
          return { stats, ghostStats, skirtPart };
        };
        for (const iso of c.isovalues) {
          const at = `${c.key} iso ${iso}`;
          pool.setRoles(null, none);
          const allStats = await surface.compute(iso);
          const all = await trianglesOf(surface, L.layout);
          expect(allStats.triangles, at).toBeGreaterThan(500);

          // S drawn, every other chunk a skirt; then just the skirts S needs, the rest idle
          const S = new Set(L.all.filter(() => rnd() < 0.4));
          const rest = new Set(L.all.filter((k) => !S.has(k)));
          const r = await check(`${at}, S drawn, the rest skirts`, S, rest, all, iso);
          expect(r.skirtPart.length, `${at}: S's skirts draw`).toBeGreaterThan(0);
          await check(`${at}, S drawn with the skirts it needs, the rest idle`, S, L.ghostsOf(S), all, iso);

          // a single drawn chunk (the one with the most triangles; chunk 0), the rest skirts
          const counts = new Map<ChunkIndex, number>();
          for (const k of all.chunks) counts.set(k, (counts.get(k) ?? 0) + 1);
          const busiest = [...counts.entries()].reduce((a, b) => (b[1] > a[1] ? b : a))[0];
          for (const one of new Set([busiest, 0])) {
            const drawn = new Set([one]);
            const one_ = await check(`${at}, chunk ${one} alone drawn`, drawn, new Set(L.all.filter((k) => k !== one)), all, iso);
            await check(`${at}, chunk ${one} alone drawn with its skirts`, drawn, L.ghostsOf(drawn), all, iso);
            if (one === busiest) expect(one_.skirtPart.length, `${at}: chunk ${one}'s skirts draw`).toBeGreaterThan(0);
          }

          // every chunk a skirt (none drawn): as every chunk a ghost, no triangle
          pool.setRoles(none, new Set(L.all));
          const ghosts = await surface.compute(iso);
          pool.setRoles(none, new Set(L.all), { skirts: true });
          expect(L.all.every((k) => pool.roleOf(k) === 'skirt')).toBe(true);
          const skirts = await surface.compute(iso);
          expect(skirts.triangles, `${at}: all skirts`).toBe(0);
          expect(skirts.occupiedBlocks).toBe(0);
          expect(skirts.vertices).toBe(ghosts.vertices);
          expect((await surface.readMesh()).indices.length).toBe(0);

          // back to every chunk drawn; skirts are not sticky
          pool.setRoles(S, rest);
          expect(L.all.map((k) => pool.roleOf(k))).toEqual(L.all.map((k) => (S.has(k) ? 'drawn' : 'ghost')));
          pool.setRoles(null, rest, { skirts: true });
          expect(L.all.every((k) => pool.roleOf(k) === 'drawn')).toBe(true);
          expect((await surface.compute(iso)).triangles).toBe(allStats.triangles);
        }
        surface.destroy();
        pool.destroy();
      },
      900_000,
    );
  }

  for (const c of cases) {
    gpuTest(
      `${c.key}: roles survive resize (chunks moved between slots by a shrink, then a grow)`,
      async ({ gpu }) => {
        const L = level(c.key);
        const iso = c.isovalues[0];
        const reference = poolOf(gpu, c.key, L.all);
        const refSurface = await Isosurface.create(gpu, reference);
        await refSurface.compute(iso);
        const all = await trianglesOf(refSurface, L.layout);
        refSurface.destroy();
        reference.destroy();
        // S: every other chunk of the bottom layer; its ghosts: the rest of that layer and the layer above
        const S = new Set(
          L.all.filter((k) => {
            const [x, y, z] = L.coords(k);
            return z === 0 && (x + y) % 2 === 0;
          }),
        );
        const needed = L.ghostsOf(S);
        const keep = new Set([...S, ...needed]);
        const expected = partOf(all, S);
        expect(expected.length).toBeGreaterThan(0);
        // the roles show: the ghosts have triangles of their own, and S without them makes fewer
        expect(all.chunks.some((k) => needed.has(k))).toBe(true);
        const alone = poolOf(gpu, c.key, S);
        const aloneSurface = await Isosurface.create(gpu, alone);
        expect((await aloneSurface.compute(iso)).triangles).toBeLessThan(expected.length);
        aloneSurface.destroy();
        alone.destroy();
        // the other chunks in the low slots, S and its ghosts above them; the others leave
        const pool = poolOf(gpu, c.key, [...L.all.filter((k) => !keep.has(k)), ...keep]);
        for (const k of L.all) if (!keep.has(k)) pool.evict(k);
        pool.setRoles(S, needed);
        const before = new Map([...keep].map((k) => [k, pool.slotOfChunk(k)!]));
        expect([...before.values()].every((slot) => slot >= L.count - keep.size)).toBe(true);
        for (const capacity of [keep.size, L.count]) {
          pool.resize(capacity);
          const surface = await Isosurface.create(gpu, pool);
          const stats = await surface.compute(iso);
          expect(sorted(await trianglesOf(surface, L.layout)), `${c.key}: after resize(${capacity})`).toEqual(expected);
          expect(stats.triangles).toBe(expected.length);
          for (const k of keep) expect(pool.roleOf(k)).toBe(S.has(k) ? 'drawn' : 'ghost');
          surface.destroy();
        }
        // the shrink moved chunks into other slots
        expect([...keep].some((k) => pool.slotOfChunk(k) !== before.get(k))).toBe(true);
        pool.destroy();
      },
      600_000,
    );
  }
});
