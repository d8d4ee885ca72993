// A cut for rays (CutInput.seen, issue 46), the step's region grid
// (regions.ts) and what the rays saw (seen.ts), against a brute-force
// reference of the rule written here: from the roots, a drawn node that holds
// a seen level-0 chunk, meets the view and whose voxels project to more than
// the tolerance is split into its seen children, and stays drawn (its voxels
// under them fill their seams; no ghosts); no balance. With no budget that set is unique.
// Then from outside: the region grid covers every region once by the finest
// drawn node over it, it is nested (a drawn chunk's parent drawn), has no
// ghosts, its wanted chunks are the drawn ones,
// a binding budget is kept, and everything seen near the eye is refined first.
import { mat4 } from 'gl-matrix';
import { describe, expect, it } from 'vitest';
import { type CutCamera, type CutInput, type CutLevel, viewCut } from '../../../src/store/view/cut.ts';
import { boxInFrustum, frustumPlanes } from '../../../src/store/view/frustum.ts';
import { finerReachVoxels } from '../../../src/raycast/seam-reach.ts';
import { NO_OWNER, regionOwners } from '../../../src/store/view/regions.ts';
import { GUARD_VOXELS, seenChunks } from '../../../src/store/view/seen.ts';

type V3 = [number, number, number];

function layout(dims0: V3, edges: number[]): CutLevel[] {
  return edges.map((edge, L) => {
    const dims = dims0.map((d) => Math.ceil(d / 2 ** L)) as V3;
    return { dims, chunkEdge: edge, chunkGrid: dims.map((d) => Math.ceil(d / edge)) as V3 };
  });
}

function lookCamera(eye: V3, target: V3, scale: number): CutCamera {
  const fov = (40 * Math.PI) / 180;
  const view = mat4.lookAt(new Float64Array(16), eye, target, [0, 1, 0]);
  const proj = mat4.perspectiveZO(new Float64Array(16), fov, 640 / 480, 0.01 * scale, 20 * scale);
  return { viewProj: mat4.multiply(new Float64Array(16), proj, view), eye, pixelsPerUnit: 480 / (2 * Math.tan(fov / 2)) };
}

// 256^3 in 16^3 chunks, levels 0..4 (every level nests 2x2x2 into the next)
const LEVELS = layout([256, 256, 256], [16, 16, 16, 16, 16]);
const G0 = LEVELS[0].chunkGrid;
const CAMERAS: { name: string; camera: CutCamera }[] = [
  { name: 'zoomed into a corner', camera: lookCamera([-10, -12, -8], [40, 30, 25], 256) },
  { name: 'looking at the +z face', camera: lookCamera([128, 115, 360], [128, 128, 256], 256) },
];

/** A seen set: level-0 chunks on a sphere shell about (cx, cy, cz) of radius r (a surface the rays hit). */
function shell(cx: number, cy: number, cz: number, r: number): Uint32Array {
  const seen = new Uint32Array(G0[0] * G0[1] * G0[2]);
  for (let z = 0; z < G0[2]; z++)
    for (let y = 0; y < G0[1]; y++)
      for (let x = 0; x < G0[0]; x++) {
        const d = Math.hypot((x + 0.5) * 16 - cx, (y + 0.5) * 16 - cy, (z + 0.5) * 16 - cz);
        if (Math.abs(d - r) < 12) seen[x + G0[0] * (y + G0[1] * z)] = 1;
      }
  return seen;
}

function input(camera: CutCamera, seen: Uint32Array, extra: Partial<CutInput> = {}): CutInput {
  return {
    levels: LEVELS,
    voxelSize: [1, 1, 1],
    camera,
    tolerancePx: 1.5,
    finest: 0,
    coarsest: LEVELS.length - 1,
    needs: () => () => true,
    chunkBytes: (L) => 1000 + L,
    budgetBytes: Infinity,
    seen,
    ...extra,
  };
}

const key = (L: number, c: number) => `${L}:${c}`;
const coordsOf = (L: number, c: number): V3 => {
  const g = LEVELS[L].chunkGrid;
  return [c % g[0], Math.floor(c / g[0]) % g[1], Math.floor(c / (g[0] * g[1]))];
};
const indexOf = (L: number, q: readonly number[]) => {
  const g = LEVELS[L].chunkGrid;
  return q[0] + g[0] * (q[1] + g[1] * q[2]);
};
/** A chunk's box in level-0 voxels. */
const boxOf = (L: number, c: number) => {
  const e = 16 * 2 ** L;
  const q = coordsOf(L, c);
  return { lo: q.map((v) => v * e) as V3, hi: q.map((v) => Math.min((v + 1) * e, 256)) as V3 };
};

/** The brute-force rule: the drawn nodes of an unlimited cut for rays. */
function reference(inp: CutInput): Set<string> {
  const planes = frustumPlanes(inp.camera.viewProj);
  const seen = inp.seen!;
  const holdsSeen = (L: number, c: number) => {
    const { lo, hi } = boxOf(L, c);
    for (let z = lo[2] / 16; z < hi[2] / 16; z++)
      for (let y = lo[1] / 16; y < hi[1] / 16; y++)
        for (let x = lo[0] / 16; x < hi[0] / 16; x++) if (seen[indexOf(0, [x, y, z])]) return true;
    return false;
  };
  const wantsSplit = (L: number, c: number) => {
    if (L === 0 || !holdsSeen(L, c)) return false;
    const { lo, hi } = boxOf(L, c);
    if (!boxInFrustum(planes, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2])) return false;
    const e = inp.camera.eye;
    const d = Math.hypot(...[0, 1, 2].map((a) => Math.max(lo[a] - e[a], 0, e[a] - hi[a])));
    return d === 0 || (2 ** L * inp.camera.pixelsPerUnit) / d > inp.tolerancePx;
  };
  const drawn = new Set<string>();
  const visit = (L: number, c: number) => {
    if (!wantsSplit(L, c)) {
      drawn.add(key(L, c));
      return;
    }
    const q = coordsOf(L, c);
    for (let z = 0; z < 2; z++)
      for (let y = 0; y < 2; y++)
        for (let x = 0; x < 2; x++) {
          const child = indexOf(L - 1, [2 * q[0] + x, 2 * q[1] + y, 2 * q[2] + z]);
          if (holdsSeen(L - 1, child)) visit(L - 1, child);
        }
    drawn.add(key(L, c));
  };
  const top = LEVELS.length - 1;
  for (let c = 0; c < LEVELS[top].chunkGrid.reduce((a, b) => a * b, 1); c++) visit(top, c);
  return drawn;
}

function drawnOf(cut: ReturnType<typeof viewCut>): Set<string> {
  const out = new Set<string>();
  cut.levels.forEach((l, L) => {
    for (const c of l.drawn) out.add(key(L, c));
  });
  return out;
}

/** Owner per level-0 chunk by brute force: the finest drawn node whose box holds it. */
function expectRegions(cut: ReturnType<typeof viewCut>): void {
  const regions = regionOwners(
    cut.levels.map((l) => l.drawn),
    LEVELS,
    LEVELS.map((_, L) => [2 ** L, 2 ** L, 2 ** L] as const),
  )!;
  const finestDrawn = cut.levels.findIndex((l) => l.drawn.length > 0);
  expect(regions.grid).toEqual(LEVELS[finestDrawn].chunkGrid);
  const e = 16 * 2 ** finestDrawn;
  for (let i = 0; i < regions.owner.length; i++) {
    const [x, y, z] = coordsOf(finestDrawn, i).map((v) => v * e);
    let best = NO_OWNER;
    cut.levels.forEach((l, L) => {
      for (const c of l.drawn) {
        const { lo, hi } = boxOf(L, c);
        if (lo[0] <= x && x < hi[0] && lo[1] <= y && y < hi[1] && lo[2] <= z && z < hi[2]) best = Math.min(best, L);
      }
    });
    // every region is drawn by some level (the roots cover the volume, a split node stays drawn where its children are not)
    expect(best).not.toBe(NO_OWNER);
    expect(regions.owner[i]).toBe(best);
  }
}

/** Ghosts and wanted chunks by their definition: +x/+y/+z and diagonal neighbours of drawn chunks, not drawn, needed. */
function expectSets(cut: ReturnType<typeof viewCut>): void {
  cut.levels.forEach((l, L) => {
    const drawn = new Set(l.drawn);
    // every drawn chunk's parent is drawn (its coarser level holds voxels under all of it)
    if (L + 1 < LEVELS.length && cut.levels[L + 1].drawn.length > 0)
      for (const c of l.drawn) {
        const q = coordsOf(L, c).map((v) => Math.floor(v / 2));
        expect(cut.levels[L + 1].drawn).toContain(indexOf(L + 1, q));
      }
    // a cut for rays is nested: no ghosts (a coarser level traces a drawn chunk's last cells)
    expect(cut.nested).toBe(true);
    expect(l.ghosts).toEqual([]);
    expect(new Set(l.wanted)).toEqual(drawn);
  });
}

describe('a cut for rays (seen)', () => {
  for (const { name, camera } of CAMERAS) {
    it(`${name}: the rule's nodes, nested, every region owned by the finest drawn node over it`, () => {
      for (const seen of [shell(128, 128, 128, 90), shell(0, 0, 0, 60)]) {
        const inp = input(camera, seen);
        const cut = viewCut(inp);
        const want = reference(inp);
        expect(drawnOf(cut)).toEqual(want);
        expect(cut.limitedByBudget).toBe(false);
        // nested: some node stays drawn under finer ones (its unseen children), and no drawn level-0 chunk is unseen
        const childOf = (L: number, c: number, o: number) =>
          key(
            L - 1,
            indexOf(
              L - 1,
              coordsOf(L, c).map((v, a) => 2 * v + ((o >> a) & 1)),
            ),
          );
        const nested = cut.levels.some(
          (l, L) => L > 0 && l.drawn.some((c) => [0, 1, 2, 3, 4, 5, 6, 7].some((o) => want.has(childOf(L, c, o)))),
        );
        expect(nested).toBe(true);
        expect(cut.levels[0].drawn.every((c) => seen[c] === 1)).toBe(true);
        expect(cut.levels[0].drawn.length).toBeGreaterThan(0);
        expectRegions(cut);
        expectSets(cut);
      }
    });
  }

  it('nothing seen: the roots only; everything seen: the cut by error alone without balance (its split nodes drawn under their children)', () => {
    const { camera } = CAMERAS[0];
    const none = viewCut(input(camera, new Uint32Array(G0[0] * G0[1] * G0[2])));
    expect(none.levels.slice(0, -1).every((l) => l.drawn.length === 0)).toBe(true);
    const every = viewCut(input(camera, new Uint32Array(G0[0] * G0[1] * G0[2]).fill(1)));
    const regions = regionOwners(
      every.levels.map((l) => l.drawn),
      LEVELS,
      LEVELS.map((_, L) => [2 ** L, 2 ** L, 2 ** L] as const),
    )!;
    // the leaves (drawn nodes with no child drawn) are a partition: their level-0 voxels add up to the
    // volume's; a split node has all its children drawn (all seen), and stays drawn under them
    const children = (L: number, c: number) =>
      [0, 1, 2, 3, 4, 5, 6, 7].map((o) => coordsOf(L, c).map((v, a) => 2 * v + ((o >> a) & 1))).map((q) => indexOf(L - 1, q));
    let voxels = 0;
    every.levels.forEach((l, L) => {
      for (const c of l.drawn) {
        const drawnChildren = L > 0 ? children(L, c).filter((u) => every.levels[L - 1].drawn.includes(u)).length : 0;
        expect([0, 8]).toContain(drawnChildren);
        if (drawnChildren === 0) voxels += (16 * 2 ** L) ** 3;
      }
    });
    expect(voxels).toBe(256 ** 3);
    expect(regions.owner.every((o) => o !== NO_OWNER)).toBe(true);
    expect(drawnOf(every)).toEqual(reference(input(camera, new Uint32Array(G0[0] * G0[1] * G0[2]).fill(1))));
  });

  it('a binding budget: kept, a subset of the unlimited refinement, near before far', () => {
    const { camera } = CAMERAS[0];
    const seen = shell(0, 0, 0, 60);
    const free = viewCut(input(camera, seen));
    const freeDrawn = drawnOf(free);
    const budgetBytes = Math.floor(free.bytes * 0.6);
    const cut = viewCut(input(camera, seen, { budgetBytes }));
    expect(cut.bytes).toBeLessThanOrEqual(budgetBytes);
    expect(cut.limitedByBudget).toBe(true);
    expectRegions(cut);
    expectSets(cut);
    // every level-0 chunk drawn is one the unlimited cut draws
    for (const c of cut.levels[0].drawn) expect(freeDrawn.has(key(0, c))).toBe(true);
    expect(cut.levels[0].drawn.length).toBeGreaterThan(0);
    expect(cut.levels[0].drawn.length).toBeLessThan(free.levels[0].drawn.length);
    // near before far: of the unlimited cut's level-0 chunks, the nearer half is drawn at least as much as the farther
    const eye = camera.eye;
    const dist = (c: number) => {
      const { lo, hi } = boxOf(0, c);
      return Math.hypot(...[0, 1, 2].map((a) => Math.max(lo[a] - eye[a], 0, eye[a] - hi[a])));
    };
    const byDistance = [...free.levels[0].drawn].sort((a, b) => dist(a) - dist(b));
    const drawn0 = new Set(cut.levels[0].drawn);
    const share = (cs: number[]) => cs.filter((c) => drawn0.has(c)).length / cs.length;
    const h = Math.floor(byDistance.length / 2);
    expect(share(byDistance.slice(0, h))).toBeGreaterThan(share(byDistance.slice(h)));
  });

  it('a binding budget: the chunks more pixels hit are refined first (before nearer ones fewer pixels hit)', () => {
    const { camera } = CAMERAS[0];
    const seen = shell(0, 0, 0, 60);
    const free = viewCut(input(camera, seen));
    const budgetBytes = Math.floor(free.bytes * 0.6);
    const flat = viewCut(input(camera, seen, { budgetBytes }));
    // the unlimited cut's level-0 chunks the flat budgeted cut leaves out get many pixels; the others one each
    const drawn0 = new Set(flat.levels[0].drawn);
    const left = free.levels[0].drawn.filter((c) => !drawn0.has(c));
    expect(left.length).toBeGreaterThan(0);
    const weighted = seen.map((v) => (v > 0 ? 2 : 0));
    for (const c of left) weighted[c] = 1 + 1000;
    const cut = viewCut(input(camera, weighted, { budgetBytes }));
    expect(cut.bytes).toBeLessThanOrEqual(budgetBytes);
    expectRegions(cut);
    expectSets(cut);
    const now = new Set(cut.levels[0].drawn);
    const share = (cs: number[]) => cs.filter((c) => now.has(c)).length / cs.length;
    // most level-0 chunks drawn now are those many pixels hit, which the flat cut left out
    expect(cut.levels[0].drawn.length).toBeGreaterThan(0);
    expect(cut.levels[0].drawn.filter((c) => left.includes(c)).length / cut.levels[0].drawn.length).toBeGreaterThan(0.5);
    expect(share(left)).toBeGreaterThan(share([...drawn0]));
  });
});

describe('seenChunks: where the rays hit', () => {
  const level0 = { dims: [256, 256, 256] as const, chunkEdge: 16, chunkGrid: G0 };
  const scales = LEVELS.map((_, L) => [2 ** L, 2 ** L, 2 ** L] as const);

  it("the hit's chunk, and the chunks GUARD_VOXELS voxels of the hit's level before and after it along the ray", () => {
    // level 2 owns everything, level 0 the chunk (0, 0, 0)
    const leaves = LEVELS.map(() => [] as number[]);
    leaves[2] = Array.from({ length: 4 ** 3 }, (_, c) => c);
    leaves[0] = [0];
    const regions = regionOwners(leaves, LEVELS, scales)!;
    expect(regions.owner[0]).toBe(0);
    expect(regions.owner[1]).toBe(2);
    // a hit at level 2 just before a chunk face along +x: the guard (2 voxels of level 2 = 8) crosses it
    const a = seenChunks(Float64Array.of(60, 40, 40), Float64Array.of(1, 0, 0), level0, regions, scales);
    const ch = (x: number, y: number, z: number) => indexOf(0, [x, y, z]);
    expect(GUARD_VOXELS * 4).toBe(8);
    expect([...a.seen.keys()].filter((i) => a.seen[i])).toEqual([ch(3, 2, 2), ch(4, 2, 2)].sort((p, q) => p - q));
    expect(a.added).toBe(2);
    // the hit's chunk counts its pixel (1 + 1), the guard's is only near one (1)
    expect(a.seen[ch(3, 2, 2)]).toBe(2);
    expect(a.seen[ch(4, 2, 2)]).toBe(1);
    // a hit at level 0: a guard of 2 voxels stays in the chunk; merged with what was seen, only the new counts
    const b = seenChunks(Float64Array.of(8, 8, 8, 9, 9, 9), Float64Array.of(0, 0.6, 0.8, 0, 0.6, 0.8), level0, regions, scales, a.seen);
    expect(b.added).toBe(1);
    expect(b.seen[ch(0, 0, 0)]).toBe(3);
    expect(b.seen[ch(3, 2, 2)]).toBe(2);
    expect(b.seen.reduce((s, v) => s + (v > 0 ? 1 : 0), 0)).toBe(3);
    // hits outside the volume count for nothing
    expect(seenChunks(Float64Array.of(-5, 300, 8), Float64Array.of(1, 0, 0), level0, regions, scales).added).toBe(0);
  });

  it("a hit just below a seam with a coarser level above may be that level's (in a nested cut its rays reach down): the chunk above counts as seen", () => {
    // level 0 owns the chunk (0, 0, 0), level 2 everything else, so (0, 1, 0) above it is level 2's
    const leaves = LEVELS.map(() => [] as number[]);
    leaves[2] = Array.from({ length: 4 ** 3 }, (_, c) => c);
    leaves[0] = [indexOf(0, [0, 0, 0])];
    const regions = regionOwners(leaves, LEVELS, scales)!;
    const ch = (x: number, y: number, z: number) => indexOf(0, [x, y, z]);
    // level 2's rays trace 1.5 of its voxels + 1/4 (6.25 level-0 voxels) below the seam at y = 16
    expect(finerReachVoxels(4)).toBe(6.25);
    const along = Float64Array.of(0, 0, 1);
    // 3 voxels below the seam, looking along +z (the guard stays in the chunk): the chunk above too
    const near = seenChunks(Float64Array.of(8, 13, 8), along, level0, regions, scales);
    expect([...near.seen.keys()].filter((i) => near.seen[i])).toEqual([ch(0, 0, 0), ch(0, 1, 0)]);
    expect(near.seen[ch(0, 0, 0)]).toBe(2);
    expect(near.seen[ch(0, 1, 0)]).toBe(1);
    // beyond the reach (7 below the seam): only the hit's chunk
    const far = seenChunks(Float64Array.of(8, 9, 8), along, level0, regions, scales);
    expect([...far.seen.keys()].filter((i) => far.seen[i])).toEqual([ch(0, 0, 0)]);
    // a diagonal seam: near the faces at x = 16 and y = 16, level 2 owning (1, 0, 0), (0, 1, 0) and (1, 1, 0)
    const corner = seenChunks(Float64Array.of(13, 14, 8), along, level0, regions, scales);
    expect([...corner.seen.keys()].filter((i) => corner.seen[i])).toEqual(
      [ch(0, 0, 0), ch(1, 0, 0), ch(0, 1, 0), ch(1, 1, 0)].sort((a, b) => a - b),
    );
    // the hit's region owned by the coarser level itself: no seam
    const coarse = seenChunks(Float64Array.of(8, 29, 4), along, level0, regions, scales);
    expect([...coarse.seen.keys()].filter((i) => coarse.seen[i])).toEqual([ch(0, 1, 0)]);
  });
});
