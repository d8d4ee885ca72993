// The view cut (src/store/view/cut.ts) against a deliberately simple
// brute-force implementation of the same rule written here (infinite budget):
// split every leaf that asks for it until none does, then split the coarser of
// every pair of touching leaves two or more levels apart until none is, in
// O(n^2). Then, from outside: every level-0 voxel is covered by exactly one
// leaf, touching leaves differ by at most one level, ghosts and wanted follow
// their definition (recomputed chunk by chunk), a binding budget is kept and
// refines near before far, a level without ranges stops refinement, a large
// store cuts fast, and the page's Fit camera (src/render/camera.ts) is the one
// cameraForBox and cameraFromView build.
import { mat4 } from 'gl-matrix';
import { describe, expect, it } from 'vitest';
import { ArcballCamera } from '../../../src/render/camera.ts';
import { encodeViewState, decodeViewState } from '../../../src/app/url-state.ts';
import { type CutCamera, type CutInput, type CutLevel, type ViewCut, viewCut } from '../../../src/store/view/cut.ts';
import {
  type Box0,
  cameraForBox,
  cameraFromView,
  fitBox0,
  PAGE_FOV_Y_RAD,
  parseCam,
  sceneRadiusOf,
} from '../../../src/store/view/camera.ts';

type V3 = [number, number, number];

/** Levels with dims ceil(dims0 / 2^L) and the given chunk edges; with `scales`, ceil(dims0 / scale_L) per axis (levels that halve only some axes). */
function layout(dims0: V3, edges: number[], scales?: V3[]): CutLevel[] {
  return edges.map((edge, L) => {
    const f = scales?.[L] ?? [2 ** L, 2 ** L, 2 ** L];
    const dims = dims0.map((d, a) => Math.ceil(d / f[a])) as V3;
    return { dims, chunkEdge: edge, chunkGrid: dims.map((d) => Math.ceil(d / edge)) as V3, ...(scales ? { scale: f } : {}) };
  });
}

/** Level L's voxel in level-0 voxels, per axis (CutLevel.scale, else 2^L). */
const scaleOf = (levels: CutLevel[], L: number): readonly [number, number, number] => levels[L].scale ?? [2 ** L, 2 ** L, 2 ** L];

const LAYOUTS: { name: string; levels: CutLevel[]; voxelSize: V3 }[] = [
  { name: '256^3 in 16^3 chunks, levels 0..4', levels: layout([256, 256, 256], [16, 16, 16, 16, 16]), voxelSize: [1, 1, 1] },
  { name: '200x130x70, partial chunks, anisotropic voxels', levels: layout([200, 130, 70], [16, 16, 16, 16]), voxelSize: [0.5, 0.5, 1.2] },
  // E = 8, 32, 32, 64, 128: level 1 splits into 4^3, level 2 into 1 (finer chunks twice as large)
  { name: '128^3, finer chunks half and twice the coarser', levels: layout([128, 128, 128], [8, 16, 8, 8, 8]), voxelSize: [1, 1, 1] },
  // E = 32, 16, 32, 64: level 1 cannot split into level 0 (E_0 = 32 does not divide 16)
  { name: '128^3, level 1 does not nest over level 0', levels: layout([128, 128, 128], [32, 8, 8, 8]), voxelSize: [2, 2, 2] },
  // ngff-zarr's per-axis scale factors: level 1 halves z only, level 2 x and y only, level 3 every axis
  {
    name: '96x80x150, levels that halve only some axes',
    levels: layout(
      [96, 80, 150],
      [8, 8, 8, 8],
      [
        [1, 1, 1],
        [1, 1, 2],
        [2, 2, 2],
        [4, 4, 4],
      ],
    ),
    voxelSize: [1, 1, 0.6],
  },
];

const VIEWPORT = { width: 640, height: 480 };

/** A plain look-at perspective camera (gl-matrix), independent of cut.ts's page camera. */
function lookCamera(eye: V3, target: V3, up: V3, scale: number, viewport = VIEWPORT, fov = PAGE_FOV_Y_RAD): CutCamera {
  const view = mat4.lookAt(new Float64Array(16), eye, target, up);
  const proj = mat4.perspectiveZO(new Float64Array(16), fov, viewport.width / viewport.height, 0.01 * scale, 20 * scale);
  return { viewProj: mat4.multiply(new Float64Array(16), proj, view), eye, pixelsPerUnit: viewport.height / (2 * Math.tan(fov / 2)) };
}

/** The scripted cameras for a layout: name, camera, and whether anything is in view. */
function cameras(levels: CutLevel[], s: V3): { name: string; camera: CutCamera; empty?: boolean }[] {
  const W = levels[0].dims.map((d, a) => d * s[a]) as V3;
  const at = (fx: number, fy: number, fz: number): V3 => [fx * W[0], fy * W[1], fz * W[2]];
  const scale = Math.max(...W);
  return [
    { name: 'whole volume framed (the page fit)', camera: cameraForBox(fitBox0(levels[0], 0), s, VIEWPORT) },
    { name: 'zoomed into a corner', camera: lookCamera(at(-0.04, -0.05, -0.03), at(0.15, 0.12, 0.1), [0, 1, 0], scale) },
    { name: 'outside, looking at the +z face', camera: lookCamera(at(0.5, 0.45, 1.4), at(0.5, 0.5, 1), [0, 1, 0], scale) },
    { name: 'inside the volume', camera: lookCamera(at(0.3, 0.6, 0.5), at(0.9, 0.7, 0.55), [0, 0, 1], scale) },
    { name: 'looking away: nothing in view', camera: lookCamera(at(0.5, 0.5, 2), at(0.5, 0.5, 3), [0, 1, 0], scale), empty: true },
  ];
}

/** Half the chunks, by a hash of (level, chunk). */
const half = (L: number) => (c: number) => {
  let h = Math.imul(c + 1, 0x9e3779b1) ^ Math.imul(L + 7, 0x85ebca6b);
  h ^= h >>> 15;
  h = Math.imul(h, 0x2c1b3c6d);
  h ^= h >>> 12;
  return (h & 1) === 0;
};
const all = () => () => true;

function input(levels: CutLevel[], voxelSize: V3, camera: CutCamera, extra: Partial<CutInput> = {}): CutInput {
  return {
    levels,
    voxelSize,
    camera,
    tolerancePx: 1.5,
    finest: 0,
    coarsest: levels.length - 1,
    needs: all,
    chunkBytes: (L) => 1000 + L,
    budgetBytes: Infinity,
    ...extra,
  };
}

// --- the brute-force reference -----------------------------------------------

interface RNode {
  L: number;
  c: V3;
  lo: V3;
  hi: V3;
}

/** What the reference met over the tests (they must exercise balancing and the frustum). */
const seen = { balancingSplits: 0, culledRefinable: 0 };

function refCut(inp: CutInput): { leaves: RNode[]; wantsRanges: number[] } {
  const { levels, voxelSize: s, camera, finest, coarsest } = inp;
  const D = levels[0].dims;
  // a chunk's edge in level-0 voxels, per axis
  const E = (L: number, a: number) => levels[L].chunkEdge * scaleOf(levels, L)[a];
  const nests = (L: number) => [0, 1, 2].every((a) => E(L, a) % E(L - 1, a) === 0);
  const node = (L: number, c: V3): RNode => ({
    L,
    c,
    lo: [c[0] * E(L, 0), c[1] * E(L, 1), c[2] * E(L, 2)],
    hi: [Math.min((c[0] + 1) * E(L, 0), D[0]), Math.min((c[1] + 1) * E(L, 1), D[1]), Math.min((c[2] + 1) * E(L, 2), D[2])],
  });
  const children = (n: RNode): RNode[] => {
    const L = n.L - 1;
    const k = [0, 1, 2].map((a) => E(n.L, a) / E(L, a));
    const out: RNode[] = [];
    for (let z = 0; z < k[2]; z++)
      for (let y = 0; y < k[1]; y++)
        for (let x = 0; x < k[0]; x++) {
          const c: V3 = [k[0] * n.c[0] + x, k[1] * n.c[1] + y, k[2] * n.c[2] + z];
          if (c.every((v, a) => v < levels[L].chunkGrid[a] && v * E(L, a) < D[a])) out.push(node(L, c));
        }
    return out;
  };
  const m = camera.viewProj;
  const inView = (n: RNode): boolean => {
    const clip: number[][] = [];
    for (const x of [n.lo[0], n.hi[0]])
      for (const y of [n.lo[1], n.hi[1]])
        for (const z of [n.lo[2], n.hi[2]]) {
          const p = [x * s[0], y * s[1], z * s[2], 1];
          clip.push([0, 1, 2, 3].map((r) => m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r] * p[3]));
        }
    const tests: ((q: number[]) => boolean)[] = [
      (q) => q[0] >= -q[3],
      (q) => q[0] <= q[3],
      (q) => q[1] >= -q[3],
      (q) => q[1] <= q[3],
      (q) => q[2] >= 0,
      (q) => q[2] <= q[3],
    ];
    return tests.every((t) => clip.some(t));
  };
  const error = (n: RNode): number => {
    let d2 = 0;
    for (let a = 0; a < 3; a++) {
      const e = camera.eye[a];
      const nearest = Math.min(Math.max(e, n.lo[a] * s[a]), n.hi[a] * s[a]);
      d2 += (e - nearest) ** 2;
    }
    // the level's largest voxel edge in world units
    const edge = Math.max(...scaleOf(levels, n.L).map((f, a) => f * s[a]));
    return d2 === 0 ? Infinity : (edge * camera.pixelsPerUnit) / Math.sqrt(d2);
  };
  const wants = new Set<number>();
  const asks = (n: RNode): boolean => {
    if (n.L <= finest || !nests(n.L) || !inView(n) || !(error(n) > inp.tolerancePx)) return false;
    if (inp.needs(n.L - 1) === null) {
      wants.add(n.L - 1);
      return false;
    }
    return true;
  };
  if (inp.needs(coarsest) === null) wants.add(coarsest);
  let leaves: RNode[] = [];
  const g = levels[coarsest].chunkGrid;
  for (let z = 0; z < g[2]; z++)
    for (let y = 0; y < g[1]; y++)
      for (let x = 0; x < g[0]; x++) {
        const c: V3 = [x, y, z];
        if (c.every((v, a) => v * E(coarsest, a) < D[a])) leaves.push(node(coarsest, c));
      }
  for (let changed = true; changed; ) {
    changed = false;
    const next: RNode[] = [];
    for (const n of leaves) {
      const ch = asks(n) ? children(n) : [];
      if (ch.length > 0) {
        next.push(...ch);
        changed = true;
      } else next.push(n);
    }
    leaves = next;
  }
  for (;;) {
    const coarser = new Set<RNode>();
    for (let i = 0; i < leaves.length; i++)
      for (let j = i + 1; j < leaves.length; j++) {
        const a = leaves[i];
        const b = leaves[j];
        if (Math.abs(a.L - b.L) >= 2 && touch(a, b)) coarser.add(a.L > b.L ? a : b);
      }
    if (coarser.size === 0) break;
    seen.balancingSplits += coarser.size;
    leaves = leaves.flatMap((n) => (coarser.has(n) ? children(n) : [n]));
  }
  // leaves kept coarse only by the frustum: in view they would have been split
  for (const n of leaves)
    if (n.L > finest && nests(n.L) && !inView(n) && error(n) > inp.tolerancePx && inp.needs(n.L - 1)) seen.culledRefinable++;
  return { leaves, wantsRanges: [...wants].sort((a, b) => a - b) };
}

const touch = (a: { lo: V3; hi: V3 }, b: { lo: V3; hi: V3 }) =>
  a.lo[0] <= b.hi[0] && b.lo[0] <= a.hi[0] && a.lo[1] <= b.hi[1] && b.lo[1] <= a.hi[1] && a.lo[2] <= b.hi[2] && b.lo[2] <= a.hi[2];

// --- checks from outside ---------------------------------------------------------

function boxOf(levels: CutLevel[], L: number, c: V3): { lo: V3; hi: V3 } {
  const E = scaleOf(levels, L).map((f) => levels[L].chunkEdge * f);
  const D = levels[0].dims;
  return { lo: c.map((v, a) => v * E[a]) as V3, hi: c.map((v, a) => Math.min((v + 1) * E[a], D[a])) as V3 };
}

function coordsOf(level: CutLevel, c: number): V3 {
  const [gx, gy] = level.chunkGrid;
  return [c % gx, Math.floor(c / gx) % gy, Math.floor(c / (gx * gy))];
}

let coverage = new Uint8Array(0);
/** Every level-0 voxel in exactly one leaf (all voxels). */
function expectCovered(levels: CutLevel[], cut: ViewCut): void {
  const [Dx, Dy, Dz] = levels[0].dims;
  if (coverage.length < Dx * Dy * Dz) coverage = new Uint8Array(Dx * Dy * Dz);
  const cov = coverage.subarray(0, Dx * Dy * Dz);
  cov.fill(0);
  for (const n of cut.nodes) {
    const { lo, hi } = boxOf(levels, n.level, n.coords);
    for (let z = lo[2]; z < hi[2]; z++)
      for (let y = lo[1]; y < hi[1]; y++) {
        const row = Dx * (y + Dy * z);
        for (let x = lo[0]; x < hi[0]; x++) cov[row + x]++;
      }
  }
  let wrong = 0;
  for (let i = 0; i < cov.length; i++) if (cov[i] !== 1) wrong++;
  expect(wrong).toBe(0);
}

function expectBalanced(levels: CutLevel[], cut: ViewCut): void {
  const boxes = cut.nodes.map((n) => ({ L: n.level, ...boxOf(levels, n.level, n.coords) }));
  let bad = 0;
  for (let i = 0; i < boxes.length; i++)
    for (let j = i + 1; j < boxes.length; j++) if (Math.abs(boxes[i].L - boxes[j].L) >= 2 && touch(boxes[i], boxes[j])) bad++;
  expect(bad).toBe(0);
}

function worldDistance(levels: CutLevel[], s: V3, eye: V3, L: number, c: V3): number {
  const { lo, hi } = boxOf(levels, L, c);
  let d2 = 0;
  for (let a = 0; a < 3; a++) d2 += Math.max(lo[a] * s[a] - eye[a], 0, eye[a] - hi[a] * s[a]) ** 2;
  return Math.sqrt(d2);
}

/** drawn, ghosts, wanted and bytes recomputed chunk by chunk from the leaves and `needs`. */
function expectSets(inp: CutInput, cut: ViewCut): void {
  const { levels } = inp;
  let bytes = 0;
  expect(cut.levels.length).toBe(levels.length);
  for (let L = 0; L < levels.length; L++) {
    const lvl = levels[L];
    const drawnHere = cut.nodes.filter((n) => n.level === L).map((n) => n.chunk);
    expect([...cut.levels[L].drawn]).toEqual([...drawnHere].sort((a, b) => a - b));
    const drawn = new Set(drawnHere);
    const need = L >= inp.finest && L <= inp.coarsest ? inp.needs(L) : null;
    const [gx, gy, gz] = lvl.chunkGrid;
    const ghosts: number[] = [];
    const wanted: number[] = [];
    for (let z = 0; z < gz; z++)
      for (let y = 0; y < gy; y++)
        for (let x = 0; x < gx; x++) {
          const c = x + gx * (y + gy * z);
          if (need ? !need(c) : !(L === inp.coarsest)) continue;
          let lower = false;
          for (const [dx, dy, dz] of [
            [-1, 0, 0],
            [0, -1, 0],
            [0, 0, -1],
            [-1, -1, 0],
            [-1, 0, -1],
            [0, -1, -1],
            [-1, -1, -1],
          ])
            if (x + dx >= 0 && y + dy >= 0 && z + dz >= 0 && drawn.has(x + dx + gx * (y + dy + gy * (z + dz)))) lower = true;
          if (!drawn.has(c) && lower) ghosts.push(c);
          if (drawn.has(c) || lower) wanted.push(c);
        }
    expect(cut.levels[L].ghosts).toEqual(ghosts);
    expect([...cut.levels[L].wanted].sort((a, b) => a - b)).toEqual(wanted);
    const d = cut.levels[L].wanted.map((c) => worldDistance(levels, inp.voxelSize, inp.camera.eye, L, coordsOf(lvl, c)));
    for (let i = 1; i < d.length; i++) expect(d[i]).toBeGreaterThanOrEqual(d[i - 1] - 1e-9);
    bytes += wanted.length * inp.chunkBytes(L);
  }
  expect(cut.bytes).toBe(bytes);
}

const leafKeys = (leaves: { L: number; c: number }[]) => leaves.map((n) => `${n.L}:${n.c}`).sort();

function expectMatchesReference(inp: CutInput, cut: ViewCut): void {
  const ref = refCut(inp);
  const { levels } = inp;
  expect(leafKeys(cut.nodes.map((n) => ({ L: n.level, c: n.chunk })))).toEqual(
    leafKeys(ref.leaves.map((n) => ({ L: n.L, c: n.c[0] + levels[n.L].chunkGrid[0] * (n.c[1] + levels[n.L].chunkGrid[1] * n.c[2]) }))),
  );
  expect(cut.wantsRanges).toEqual(ref.wantsRanges);
  for (const n of cut.nodes) expect(n.coords).toEqual(coordsOf(levels[n.level], n.chunk));
  expect(cut.limitedByBudget).toBe(false);
}

// --- the tests ----------------------------------------------------------------------

describe('view cut against a brute-force reference (infinite budget)', () => {
  for (const { name, levels, voxelSize } of LAYOUTS) {
    describe(name, () => {
      for (const cam of cameras(levels, voxelSize)) {
        for (const [needsName, needs] of [
          ['every chunk needed', all],
          ['a random half needed', half],
        ] as const) {
          it(`${cam.name}, ${needsName}`, () => {
            for (const tolerancePx of [1.5, 5]) {
              const inp = input(levels, voxelSize, cam.camera, { needs, tolerancePx });
              const cut = viewCut(inp);
              expectMatchesReference(inp, cut);
              expectCovered(levels, cut);
              expectBalanced(levels, cut);
              expectSets(inp, cut);
              const coarsest = levels.length - 1;
              if (cam.empty) {
                expect(cut.nodes.every((n) => n.level === coarsest && !n.inView)).toBe(true);
              } else {
                expect(cut.nodes.some((n) => n.inView)).toBe(true);
                // somewhere refined, unless the layout's coarsest cannot be
                if (tolerancePx === 1.5 && cut.notes.length === 0)
                  expect(Math.min(...cut.nodes.map((n) => n.level))).toBeLessThan(coarsest);
              }
            }
          });
        }
      }
    });
  }

  it('the cases above needed the balancing and the frustum (the reference split for balance, and kept regions out of view coarse)', () => {
    expect(seen.balancingSplits).toBeGreaterThan(0);
    expect(seen.culledRefinable).toBeGreaterThan(0);
    console.log(`reference: ${seen.balancingSplits} splits for balance, ${seen.culledRefinable} leaves kept coarse by the frustum`);
  });

  it('a level that does not nest is final, and a note says so', () => {
    const { levels, voxelSize } = LAYOUTS[3];
    const inp = input(levels, voxelSize, cameras(levels, voxelSize)[1].camera);
    const cut = viewCut(inp);
    expect(cut.notes.some((n) => n.includes('level 1 is final'))).toBe(true);
    expect(cut.nodes.some((n) => n.level === 1)).toBe(true);
    expect(cut.nodes.some((n) => n.level === 0)).toBe(false);
  });

  it('finest and coarsest bound the levels used', () => {
    const { levels, voxelSize } = LAYOUTS[0];
    for (const cam of cameras(levels, voxelSize)) {
      const inp = input(levels, voxelSize, cam.camera, { finest: 1, coarsest: 3, needs: half });
      const cut = viewCut(inp);
      expectMatchesReference(inp, cut);
      expectCovered(levels, cut);
      expectBalanced(levels, cut);
      expectSets(inp, cut);
      expect(cut.nodes.every((n) => n.level >= 1 && n.level <= 3)).toBe(true);
    }
  });
});

describe('levels without ranges', () => {
  it('a level whose needs is null stops refinement and is listed in wantsRanges', () => {
    const { levels, voxelSize } = LAYOUTS[0];
    for (const cam of cameras(levels, voxelSize).filter((c) => !c.empty)) {
      const inp = input(levels, voxelSize, cam.camera, { needs: (L) => (L <= 1 ? null : all()) });
      const cut = viewCut(inp);
      expectMatchesReference(inp, cut);
      expectCovered(levels, cut);
      expect(cut.nodes.every((n) => n.level >= 2)).toBe(true);
      expect(cut.nodes.some((n) => n.level === 2)).toBe(true);
      expect(cut.wantsRanges).toEqual([1]);
    }
    // nothing in view: nothing would be refined, nothing asked for
    const away = cameras(levels, voxelSize).find((c) => c.empty)!;
    expect(viewCut(input(levels, voxelSize, away.camera, { needs: (L) => (L <= 1 ? null : all()) })).wantsRanges).toEqual([]);
  });

  it('the coarsest level without ranges: listed, and all its drawn and ghost chunks wanted', () => {
    const { levels, voxelSize } = LAYOUTS[1];
    const inp = input(levels, voxelSize, cameras(levels, voxelSize)[0].camera, { needs: (L) => (L === 3 ? null : half(L)) });
    const cut = viewCut(inp);
    expect(cut.wantsRanges).toEqual([3]);
    expectMatchesReference(inp, cut);
    const inp2 = input(levels, voxelSize, cameras(levels, voxelSize)[4].camera, { needs: (L) => (L === 3 ? null : half(L)) });
    const cut2 = viewCut(inp2);
    expect(cut2.levels[3].wanted.length).toBe(levels[3].chunkGrid.reduce((a, b) => a * b));
    expectSets(inp2, cut2);
  });
});

describe('budget', () => {
  for (const { name, levels, voxelSize } of LAYOUTS.slice(0, 3)) {
    it(`${name}: kept, coarser than without, near before far`, () => {
      for (const cam of cameras(levels, voxelSize).slice(0, 4)) {
        for (const needs of [all, half]) {
          const free = viewCut(input(levels, voxelSize, cam.camera, { needs }));
          const freeBoxes = free.nodes.map((f) => ({ L: f.level, ...boxOf(levels, f.level, f.coords) }));
          for (const fraction of [0.3, 0.6]) {
            const budgetBytes = Math.floor(free.bytes * fraction);
            const inp = input(levels, voxelSize, cam.camera, { needs, budgetBytes });
            const cut = viewCut(inp);
            expect(cut.bytes).toBeLessThanOrEqual(budgetBytes);
            expect(cut.limitedByBudget).toBe(true);
            expectCovered(levels, cut);
            expectBalanced(levels, cut);
            expectSets(inp, cut);
            // never finer than the unlimited cut: each leaf holds leaves of it (or is one)
            for (const n of cut.nodes) {
              const { lo } = boxOf(levels, n.level, n.coords);
              const holder = freeBoxes.find(
                (b) => b.lo[0] <= lo[0] && lo[0] < b.hi[0] && b.lo[1] <= lo[1] && lo[1] < b.hi[1] && b.lo[2] <= lo[2] && lo[2] < b.hi[2],
              )!;
              expect(holder.L).toBeLessThanOrEqual(n.level);
            }
            // the nearest leaf is among the finest, and the near quarter is finer than the far quarter
            const byDistance = [...cut.nodes].sort((a, b) => a.distance - b.distance);
            const finest = Math.min(...cut.nodes.map((n) => n.level));
            expect(byDistance[0].level).toBe(finest);
            const q = Math.max(1, Math.floor(byDistance.length / 4));
            const mean = (ns: typeof byDistance) => ns.reduce((s, n) => s + n.level, 0) / ns.length;
            expect(mean(byDistance.slice(0, q))).toBeLessThanOrEqual(mean(byDistance.slice(-q)));
          }
        }
      }
    });
  }

  it('a budget the coarsest level alone exceeds: the roots, limited, a note', () => {
    const { levels, voxelSize } = LAYOUTS[0];
    const cut = viewCut(input(levels, voxelSize, cameras(levels, voxelSize)[0].camera, { budgetBytes: 10 }));
    expect(cut.nodes.every((n) => n.level === 4)).toBe(true);
    expect(cut.limitedByBudget).toBe(true);
    expect(cut.notes.some((n) => n.includes('over the budget'))).toBe(true);
  });
});

describe('speed', () => {
  it('2048^3 in 64^3 chunks (levels 0..5), the camera close to a corner', () => {
    const levels = layout([2048, 2048, 2048], [64, 64, 64, 64, 64, 64]);
    const s: V3 = [1, 1, 1];
    const vp = { width: 1920, height: 1080 };
    const cams = {
      'near a corner, outside': lookCamera([-30, -20, -40], [1024, 1024, 1024], [0, 1, 0], 2048, vp),
      'at a corner, inside': lookCamera([40, 50, 30], [1024, 900, 1100], [0, 1, 0], 2048, vp),
      'the page fit': cameraForBox(fitBox0(levels[0], 0), s, vp),
    };
    for (const [name, camera] of Object.entries(cams)) {
      const inp = input(levels, s, camera, { needs: half, chunkBytes: () => 300_000 });
      let first = 0;
      let best = Infinity;
      let cut!: ViewCut;
      for (let i = 0; i < 5; i++) {
        const t0 = performance.now();
        cut = viewCut(inp);
        const ms = performance.now() - t0;
        if (i === 0) first = ms;
        best = Math.min(best, ms);
      }
      const perLevel = cut.levels.map((l) => l.drawn.length).join('/');
      console.log(
        `view cut 2048^3, ${name}: ${cut.nodes.length} leaves (per level ${perLevel}), first ${first.toFixed(1)} ms, best ${best.toFixed(1)} ms`,
      );
      expect(first).toBeLessThan(2000);
      expect(best).toBeLessThan(200);
      // close to the volume, level 0 is drawn; the page's fit of the whole volume stays coarser
      expect(cut.nodes.some((n) => n.level === 0)).toBe(name !== 'the page fit');
      // a budget: the same, limited
      const t0 = performance.now();
      const limited = viewCut({ ...inp, budgetBytes: cut.bytes / 3 });
      const ms = performance.now() - t0;
      console.log(`  with a third of its bytes as the budget: ${limited.nodes.length} leaves, ${ms.toFixed(1)} ms`);
      expect(limited.bytes).toBeLessThanOrEqual(cut.bytes / 3);
      expect(ms).toBeLessThan(2000);
    }
    // the whole coverage on a sample of voxels for the corner camera
    const cut = viewCut(input(levels, s, cams['near a corner, outside'], { needs: half }));
    let seed = 12345;
    const rnd = (n: number) => (seed = (Math.imul(seed, 1103515245) + 12345) >>> 0) % n;
    const boxes = cut.nodes.map((n) => boxOf(levels, n.level, n.coords));
    for (let i = 0; i < 2000; i++) {
      const p = [rnd(2048), rnd(2048), rnd(2048)];
      expect(boxes.filter((b) => p.every((v, a) => b.lo[a] <= v && v < b.hi[a])).length).toBe(1);
    }
    expectBalanced(levels, cut);
  });
});

describe("the page's camera", () => {
  const clipOf = (m: ArrayLike<number>, p: V3) => [0, 1, 2, 3].map((r) => m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r]);
  const boxes: { box: Box0; s: V3; vp: { width: number; height: number } }[] = [
    { box: [0, 0, 0, 255, 255, 255], s: [1, 1, 1], vp: { width: 800, height: 600 } },
    { box: [0, 0, 0, 199, 129, 69], s: [0.5, 0.5, 1.2], vp: { width: 600, height: 900 } },
    { box: [10, 20, 30, 40, 400, 50], s: [3, 1, 0.25], vp: { width: 1920, height: 1080 } },
  ];

  it('cameraForBox frames the box: its 8 corners project inside the viewport (a portrait one: inside its height)', () => {
    for (const { box, s, vp } of boxes)
      for (const up of ['x', 'y', 'z'] as const) {
        const cam = cameraForBox(box, s, vp, PAGE_FOV_Y_RAD, up);
        // the page fits the box's bounding sphere in the vertical field of view only: a canvas taller
        // than wide shows its middle, up to height / width of the width (as the page does)
        const xMax = Math.max(1, vp.height / vp.width);
        for (const x of [box[0], box[3]])
          for (const y of [box[1], box[4]])
            for (const z of [box[2], box[5]]) {
              const [cx, cy, cz, w] = clipOf(cam.viewProj, [x * s[0], y * s[1], z * s[2]]);
              expect(w).toBeGreaterThan(0);
              expect(Math.abs(cx / w)).toBeLessThanOrEqual(xMax);
              expect(Math.abs(cy / w)).toBeLessThanOrEqual(1);
              expect(cz / w).toBeGreaterThanOrEqual(0);
              expect(cz / w).toBeLessThanOrEqual(1);
            }
        expect(cam.pixelsPerUnit).toBeCloseTo(vp.height / (2 * Math.tan(PAGE_FOV_Y_RAD / 2)), 9);
        // the eye looks at the box centre
        const centre: V3 = [((box[0] + box[3]) * s[0]) / 2, ((box[1] + box[4]) * s[1]) / 2, ((box[2] + box[5]) * s[2]) / 2];
        const [cx, cy, , w] = clipOf(cam.viewProj, centre);
        expect(Math.abs(cx / w)).toBeLessThan(1e-5);
        expect(Math.abs(cy / w)).toBeLessThan(1e-5);
      }
  });

  it("is the page's ArcballCamera.fit: same state, matrices and eye (y up: from +z)", () => {
    for (const { box, s, vp } of boxes)
      for (const up of ['x', 'y', 'z'] as const) {
        const page = new ArcballCamera();
        page.aspect = vp.width / vp.height; // as the viewer's frameUniformData sets it
        page.fit({ min: [box[0] * s[0], box[1] * s[1], box[2] * s[2]], max: [box[3] * s[0], box[4] * s[1], box[5] * s[2]] }, up);
        const ours = cameraForBox(box, s, vp, PAGE_FOV_Y_RAD, up);
        expect(ours.state).toEqual(page.getState());
        expect(ours.fovYRad).toBe(page.fovY);
        const m = page.viewProjection();
        const scale = Math.max(...Array.from(m, Math.abs));
        for (let i = 0; i < 16; i++) expect(Math.abs(ours.viewProj[i] - m[i])).toBeLessThan(1e-5 * scale);
        const eye = page.eyePosition();
        for (let a = 0; a < 3; a++) expect(ours.eye[a]).toBeCloseTo(eye[a], 3);
        if (up === 'y') {
          // from the +z side: the eye is beyond the box's far z face's centre plane
          expect(ours.eye[2]).toBeGreaterThan(((box[2] + box[5]) * s[2]) / 2);
          expect(ours.up[1]).toBeGreaterThan(0.5);
        }
      }
  });

  it('cameraFromView(page.getState()) is the page camera after orbit, pan and zoom, and through the link', () => {
    const { box, s, vp } = boxes[1];
    const page = new ArcballCamera();
    page.aspect = vp.width / vp.height;
    const bounds = { min: [0, 0, 0] as V3, max: [box[3] * s[0], box[4] * s[1], box[5] * s[2]] as V3 };
    page.fit(bounds, 'y');
    page.rotateArcball(0.1, 0.2, -0.3, 0.25);
    page.pan(0.2, -0.1);
    page.zoom(0.4);
    const radius = sceneRadiusOf(box, s);
    const ours = cameraFromView(page.getState(), vp, radius);
    const m = page.viewProjection();
    const scale = Math.max(...Array.from(m, Math.abs));
    for (let i = 0; i < 16; i++) expect(Math.abs(ours.viewProj[i] - m[i])).toBeLessThan(1e-5 * scale);
    const eye = page.eyePosition();
    for (let a = 0; a < 3; a++) expect(ours.eye[a]).toBeCloseTo(eye[a], 3);
    // the link's cam= gives the same camera, to its 7 digits
    const cam = new URLSearchParams(encodeViewState({ camera: page.getState() })).get('cam')!;
    const parsed = parseCam(cam)!;
    expect(parsed).toEqual(decodeViewState(`#cam=${cam}`).camera);
    const fromLink = cameraFromView(parsed, vp, radius);
    for (let i = 0; i < 16; i++) expect(Math.abs(fromLink.viewProj[i] - m[i])).toBeLessThan(1e-4 * scale);
    expect(parseCam('1,2,3')).toBeNull();
    expect(parseCam('0,0,0,1,0,0,0,-1')).toBeNull();
  });

  it('fitBox0 is the box the page fits for a store level: (dims_L - 1) * 2^L level-0 voxels', () => {
    const levels = layout([200, 130, 70], [16, 16, 16]);
    expect(fitBox0(levels[0], 0)).toEqual([0, 0, 0, 199, 129, 69]);
    expect(fitBox0(levels[2], 2)).toEqual([0, 0, 0, 49 * 4, 32 * 4, 17 * 4]);
  });
});
