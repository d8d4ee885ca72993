// The view cut of a multi-level store: which level to draw where, for a
// camera, so that no voxel of the drawn level projects to more than
// `tolerancePx` pixels where a finer level is allowed, within a byte budget.
//
// Coordinates.
// - Level-0 voxel space: level 0's voxel (i, j, k), i in [0, dims0[0]) and so
//   on (x fastest). A level-L voxel covers scale_L level-0 voxels per axis
//   (CutLevel.scale: 2^L on every axis unless a level halves only some).
// - The octree: level L's chunk (cx, cy, cz) (ChunkIndex c = cx + gx * (cy +
//   gy * cz), src/zfp/chunked-volume.ts) is the node (L, c) covering the
//   half-open level-0 box [c * E_L, (c + 1) * E_L) per axis, E_L = chunkEdge_L *
//   scale_L (per axis), clipped to level 0's dims. Chunks whose box starts at or past level
//   0's dims cover nothing and are left out of the tree.
// - World: level-0 voxel (i, j, k) at (i * sx, j * sy, k * sz), voxelSize =
//   [sx, sy, sz]. It is the page's world: the page draws level L's voxel
//   (i, j, k) at (i, j, k) * voxelSize * 2^L (src/app/store/store-view.ts gives
//   level L the spacing voxelSize * 2^L; src/app/session.ts draws voxel v at
//   v * spacing), i.e. level-0 voxel index * voxelSize. (A voxel size the user
//   types in the panel or gives with the link's vox= is the size of the shown
//   level's voxel: pass it divided by 2^L as the level-0 voxelSize.) A node's
//   world box is [lo * s, hi * s] with [lo, hi) its clipped level-0 box.
// - Camera: the page's arcball camera (src/render/camera.ts, which this layer
//   may not import: the math is repeated in camera.ts and checked against it in
//   tests/unit/store/view-cut.test.ts). Its state (the link's cam=qx,qy,qz,qw,
//   tx,ty,tz,d) is a rotation (world -> eye), a target and a distance: eye =
//   R^-1 (0, 0, d) + target, view = T(0, 0, -d) R T(-target), projection =
//   perspectiveZO(fovY = 40°, width / height, near, far) with near = max(d -
//   1.5 r, 0.01 d, 1e-4), far = d + 1.5 r, r the radius of the box the page
//   last fitted (half its diagonal). WebGPU clip space: x, y in [-w, w], z in
//   [0, w]. The page fits the box min 0, max (dims_L - 1) * spacing_L of the
//   shown level L, i.e. level-0 voxels [0, (dims_L - 1) * 2^L] (`fitBox0`).
//   Pixels are device pixels (the canvas' width and height).
//
// The rule (viewCut). Node (L, c) is split into its children (level L-1's
// chunks inside it) when L > finest, level L-1 nests in level L (E_L a
// multiple of E_{L-1} on every axis: 1, 2, 4... children per axis; else level
// L is final and a note says so), needs(L-1) is known, the node's world box
// meets the view frustum (a conservative box-vs-6-planes test), its error
// max over axes of (scale_L * voxelSize) * pixelsPerUnit /
// distance (distance from the eye to the box, 0 inside it: error Infinity)
// exceeds tolerancePx, and the budget allows it. Splits go by a priority
// queue: nodes in the middle of the view first (a cone from the eye to the
// sphere of `CutCamera.focus`, not beyond it) by error, so nearest first;
// then the others by error / (1 + (s / D)^2)^2, s the box's distance from
// the cone's axis, D the focus' from the eye (ties: nearer first, then level,
// then chunk). So a budget that binds goes to what the view
// frames, front to back, then to the edges of the view
// (src/store/view/README.md). The cut is
// 2:1 balanced (leaves whose closed boxes touch differ by at most one level):
// before a node is split, the coarser leaves around it are split first
// (forced splits, which ignore error and frustum). A split with its forced
// splits that would make the wanted chunks cost more than the budget is undone
// whole, and the queue goes on.
//
// A cut for rays (`CutInput.seen`, issue 46: where an image's rays found the
// surface). Rays need no 2:1 balance (each ray goes on in whatever level owns
// the next region) and no finer brick where no ray hits: a node is queued
// only when a seen level-0 chunk lies inside it (in the view's middle first,
// then those more of the image's pixels hit inside, then by error), a
// split draws only its seen children, and a node split so keeps being drawn (PARTIAL) for the rest of
// its region: the cut is nested, each region drawn by the finest level
// whose drawn chunk covers it (regions.ts). No balance, no forced splits.
// Nor ghosts: a split node stays drawn even when all its children are, so
// every drawn chunk's coarser ancestors are drawn, and where a drawn chunk's
// next chunk is not, the coarser level owning the region there traces the
// drawn chunk's last cells from its own voxels (ray_blocks_pool.wgsl) rather
// than the finer level from a ghost: a ghost is a whole chunk held for one
// voxel layer, and a nested cut of scattered chunks needs more ghosts than
// drawn chunks; the kept parents cost one chunk per split.

import type { ChunkIndex } from '../types.ts';
import type { CutInput, CutLevelSets, CutNode, ViewCut } from './cut-types.ts';
import { boxInFrustum, frustumPlanes } from './frustum.ts';
import { seenPixels } from './seen.ts';

export type { CutCamera, CutInput, CutLevel, CutLevelSets, CutNode, ViewCut } from './cut-types.ts';

const ABSENT = 0;
const LEAF = 1;
const SPLIT = 2;
/** Split for rays, only some children drawn: still drawn itself, for the regions its undrawn children leave. */
const PARTIAL = 3;

interface LevelState {
  gx: number;
  gy: number;
  gz: number;
  /** ABSENT / LEAF / SPLIT per chunk. */
  state: Uint8Array;
  /** Per chunk, how many of c - {0,1}^3 (itself included) are drawn: wanted iff needed and > 0. */
  cover: Uint8Array;
  need: ((chunk: ChunkIndex) => boolean) | null;
  bytes: number;
  /** Drawn chunks. */
  leaves: number;
}

/** The view cut (see the top of this file for the rule and the coordinates). */
export function viewCut(input: CutInput): ViewCut {
  const { levels, voxelSize, camera, tolerancePx, finest, coarsest, budgetBytes } = input;
  const n = levels.length;
  if (n === 0) throw new RangeError('viewCut: no levels');
  if (!(Number.isInteger(finest) && Number.isInteger(coarsest) && finest >= 0 && finest <= coarsest && coarsest < n)) {
    throw new RangeError(`viewCut: levels ${finest}..${coarsest} are not within 0..${n - 1}`);
  }
  const [Dx, Dy, Dz] = levels[0].dims;
  const [sx, sy, sz] = voxelSize;
  const [ex, ey, ez] = camera.eye;
  const ppu = camera.pixelsPerUnit;
  // the view's middle: a cone about the eye -> focus axis, as wide as the focus sphere at its end
  const focus = camera.focus;
  const focusDistance = focus ? Math.hypot(focus.point[0] - ex, focus.point[1] - ey, focus.point[2] - ez) : 0;
  const axis = focus && focusDistance > 0 ? focus.point.map((p, a) => (p - camera.eye[a]) / focusDistance) : null;
  const scale = levels.map((l, L) => l.scale ?? [2 ** L, 2 ** L, 2 ** L]);
  // a level's chunk edge in level-0 voxels, per axis, and its voxel's largest world edge
  const E = levels.map((l, L) => scale[L].map((f) => l.chunkEdge * f) as [number, number, number]);
  const voxelEdge = scale.map((f) => Math.max(f[0] * sx, f[1] * sy, f[2] * sz));
  const notes: string[] = [];
  // a cut for rays: per level and chunk, whether a seen level-0 chunk lies inside, and the pixels hitting inside
  const seen = input.seen ?? null;
  const seenAt: ({ any: Uint8Array; pixels: Float64Array } | undefined)[] = new Array(n);
  const seenOf = (L: number): { any: Uint8Array; pixels: Float64Array } => {
    let m = seenAt[L];
    if (!m) {
      const [gx, gy, gz] = levels[L].chunkGrid;
      const [hx, hy] = levels[0].chunkGrid;
      m = { any: new Uint8Array(gx * gy * gz), pixels: new Float64Array(gx * gy * gz) };
      for (let i = 0; i < seen!.length; i++) {
        if (!seen![i]) continue;
        const q = [i % hx, Math.floor(i / hx) % hy, Math.floor(i / (hx * hy))];
        const x = Math.floor((q[0] * E[0][0]) / E[L][0]);
        const y = Math.floor((q[1] * E[0][1]) / E[L][1]);
        const z = Math.floor((q[2] * E[0][2]) / E[L][2]);
        if (x >= gx || y >= gy || z >= gz) continue;
        const u = x + gx * (y + gy * z);
        m.any[u] = 1;
        m.pixels[u] += seenPixels(seen![i]);
      }
      seenAt[L] = m;
    }
    return m;
  };
  const seenIn = (L: number, c: number): boolean => seenOf(L).any[c] === 1;

  // k[L]: children per axis when level L splits into L-1 (null: level L is final)
  const k: ([number, number, number] | null)[] = new Array(n).fill(null);
  for (let L = finest + 1; L <= coarsest; L++) {
    const per = E[L].map((e, a) => e / E[L - 1][a]);
    if (per.every((v) => Number.isInteger(v) && v >= 1)) k[L] = per as [number, number, number];
    else
      notes.push(
        `level ${L} is final: its chunks (${E[L].join(' x ')} level-0 voxels) are not made of level ${L - 1}'s (${E[L - 1].join(' x ')} level-0 voxels), so it cannot be refined`,
      );
  }

  const planes = frustumPlanes(camera.viewProj);
  const lv: (LevelState | undefined)[] = new Array(n);
  const needsAsked = new Uint8Array(n);
  const needs: (((chunk: ChunkIndex) => boolean) | null)[] = new Array(n).fill(null);
  const needsOf = (L: number) => {
    if (!needsAsked[L]) {
      needsAsked[L] = 1;
      needs[L] = input.needs(L);
    }
    return needs[L];
  };
  const levelState = (L: number): LevelState => {
    let s = lv[L];
    if (!s) {
      const [gx, gy, gz] = levels[L].chunkGrid;
      s = {
        gx,
        gy,
        gz,
        state: new Uint8Array(gx * gy * gz),
        cover: new Uint8Array(gx * gy * gz),
        need: needsOf(L),
        bytes: input.chunkBytes(L),
        leaves: 0,
      };
      lv[L] = s;
    }
    return s;
  };

  let bytes = 0;
  // --- wanted bookkeeping: a drawn change of c touches c + {0,1}^3 (its ghosts), or c alone in a cut
  // for rays: nested, every drawn chunk's ancestors are drawn too, and a coarser level's rays trace its
  // last cells where the next chunk is not drawn (shaders/render/ray_blocks_pool.wgsl), so no ghosts
  const reach = seen === null ? 2 : 1;
  const changeDrawn = (s: LevelState, c: number, delta: 1 | -1): void => {
    const { gx, gy, gz, cover, need } = s;
    s.leaves += delta;
    const cx = c % gx;
    const cy = Math.floor(c / gx) % gy;
    const cz = Math.floor(c / (gx * gy));
    const sxy = gx * gy;
    for (let dz = 0; dz < reach; dz++) {
      if (cz + dz >= gz) break;
      for (let dy = 0; dy < reach; dy++) {
        if (cy + dy >= gy) break;
        for (let dx = 0; dx < reach; dx++) {
          if (cx + dx >= gx) break;
          const u = c + dx + dy * gx + dz * sxy;
          if (delta > 0) {
            if (cover[u]++ === 0 && (need === null || need(u))) bytes += s.bytes;
          } else if (--cover[u] === 0 && (need === null || need(u))) bytes -= s.bytes;
        }
      }
    }
  };

  // --- node geometry (written to these by evalNode)
  let nInView = false;
  let nDist = 0;
  let nErr = 0;
  /** The split priority: whether the box meets the focus, then its error weighed down by its distance from the focus. */
  let nFocused = true;
  let nPriority = 0;
  const evalNode = (L: number, cx: number, cy: number, cz: number): void => {
    const [ex0, ey0, ez0] = E[L];
    const x0 = cx * ex0 * sx;
    const y0 = cy * ey0 * sy;
    const z0 = cz * ez0 * sz;
    const x1 = Math.min((cx + 1) * ex0, Dx) * sx;
    const y1 = Math.min((cy + 1) * ey0, Dy) * sy;
    const z1 = Math.min((cz + 1) * ez0, Dz) * sz;
    nInView = boxInFrustum(planes, x0, y0, z0, x1, y1, z1);
    const dx = Math.max(x0 - ex, 0, ex - x1);
    const dy = Math.max(y0 - ey, 0, ey - y1);
    const dz = Math.max(z0 - ez, 0, ez - z1);
    nDist = Math.sqrt(dx * dx + dy * dy + dz * dz);
    nErr = nDist > 0 ? (voxelEdge[L] * ppu) / nDist : Infinity;
    nPriority = nErr;
    nFocused = true;
    if (axis && focus) {
      // the middle of the view up to the focus: a cone from the eye to the focus sphere. The point of
      // its axis nearest the box's centre, and the box's distance from it against the cone's radius there
      const cx = (x0 + x1) / 2 - ex;
      const cy = (y0 + y1) / 2 - ey;
      const cz = (z0 + z1) / 2 - ez;
      const t = Math.min(1, Math.max(0, (cx * axis[0] + cy * axis[1] + cz * axis[2]) / focusDistance));
      const qx = ex + axis[0] * t * focusDistance;
      const qy = ey + axis[1] * t * focusDistance;
      const qz = ez + axis[2] * t * focusDistance;
      const fx = Math.max(x0 - qx, 0, qx - x1);
      const fy = Math.max(y0 - qy, 0, qy - y1);
      const fz = Math.max(z0 - qz, 0, qz - z1);
      const f = Math.sqrt(fx * fx + fy * fy + fz * fz);
      nFocused = f <= focus.radius * t;
      // the others: nearer the middle first
      const r = (f * f) / (focusDistance * focusDistance);
      nPriority = nFocused ? nErr : nErr / ((1 + r) * (1 + r));
    }
  };

  // --- the tree
  const canSplit = (L: number, cx: number, cy: number, cz: number): boolean => {
    const kk = k[L];
    if (L <= finest || kk === null || needsOf(L - 1) === null) return false;
    const [gx, gy, gz] = levels[L - 1].chunkGrid;
    return kk[0] * cx < gx && kk[1] * cy < gy && kk[2] * cz < gz;
  };
  const logL: number[] = [];
  const logC: number[] = [];
  /** Calls fn(childChunk) for each child of (L, c) (chunks of L-1 inside it, within L-1's grid and level 0's dims). */
  const forChildren = (L: number, c: number, fn: (s: LevelState, child: number) => void): void => {
    const p = lv[L]!;
    const cx = c % p.gx;
    const cy = Math.floor(c / p.gx) % p.gy;
    const cz = Math.floor(c / (p.gx * p.gy));
    const s = levelState(L - 1);
    const [kx, ky, kz] = k[L]!;
    const e = E[L - 1];
    const xEnd = Math.min(kx * cx + kx, s.gx, Math.ceil(Dx / e[0]));
    const yEnd = Math.min(ky * cy + ky, s.gy, Math.ceil(Dy / e[1]));
    const zEnd = Math.min(kz * cz + kz, s.gz, Math.ceil(Dz / e[2]));
    for (let z = kz * cz; z < zEnd; z++)
      for (let y = ky * cy; y < yEnd; y++) for (let x = kx * cx; x < xEnd; x++) fn(s, x + s.gx * (y + s.gy * z));
  };
  const drawChild = (s: LevelState, child: number): void => {
    s.state[child] = LEAF;
    changeDrawn(s, child, 1);
  };
  const undrawChild = (s: LevelState, child: number): void => {
    s.state[child] = ABSENT;
    changeDrawn(s, child, -1);
  };
  const split = (L: number, c: number): void => {
    const s = lv[L]!;
    let all = true;
    forChildren(L, c, (cs, child) => {
      if (seen === null || seenIn(L - 1, child)) drawChild(cs, child);
      else all = false;
    });
    // a cut for rays keeps every split node drawn, even with all its children drawn: its voxels under
    // them are what its rays trace their seams toward it from (cut.ts' top, `nested`)
    const keep = seen !== null || !all;
    s.state[c] = keep ? PARTIAL : SPLIT;
    if (!keep) changeDrawn(s, c, -1);
    logL.push(L);
    logC.push(c);
  };
  const undoTo = (mark: number): void => {
    while (logL.length > mark) {
      const L = logL.pop()!;
      const c = logC.pop()!;
      // a rays' split drew only its seen children
      forChildren(L, c, (cs, child) => {
        if (cs.state[child] === LEAF) undrawChild(cs, child);
      });
      const s = lv[L]!;
      if (s.state[c] === SPLIT) changeDrawn(s, c, 1);
      s.state[c] = LEAF;
    }
  };

  // the leaf holding a level-0 voxel (written to locL / locC)
  let locL = 0;
  let locC = 0;
  const locate = (px: number, py: number, pz: number): boolean => {
    for (let L = coarsest; L >= finest; L--) {
      const s = lv[L];
      if (!s) return false;
      const x = Math.floor(px / E[L][0]);
      const y = Math.floor(py / E[L][1]);
      const z = Math.floor(pz / E[L][2]);
      if (x >= s.gx || y >= s.gy || z >= s.gz) return false;
      const c = x + s.gx * (y + s.gy * z);
      const st = s.state[c];
      if (st === LEAF) {
        locL = L;
        locC = c;
        return true;
      }
      if (st !== SPLIT) return false;
    }
    return false;
  };

  /** Splits every leaf at level >= L + 1 touching node (L; cx, cy, cz): each contains one of its 26 same-size neighbours. */
  const balanceAround = (L: number, cx: number, cy: number, cz: number): void => {
    const e = E[L];
    for (let dz = -1; dz <= 1; dz++) {
      const pz = (cz + dz) * e[2];
      if (pz < 0 || pz >= Dz) continue;
      for (let dy = -1; dy <= 1; dy++) {
        const py = (cy + dy) * e[1];
        if (py < 0 || py >= Dy) continue;
        for (let dx = -1; dx <= 1; dx++) {
          if (dx === 0 && dy === 0 && dz === 0) continue;
          const px = (cx + dx) * e[0];
          if (px < 0 || px >= Dx) continue;
          while (locate(px, py, pz) && locL > L) {
            if (!forceSplit(locL, locC)) break;
          }
        }
      }
    }
  };
  const forceSplit = (L: number, c: number): boolean => {
    const s = lv[L]!;
    const cx = c % s.gx;
    const cy = Math.floor(c / s.gx) % s.gy;
    const cz = Math.floor(c / (s.gx * s.gy));
    if (!canSplit(L, cx, cy, cz)) return false;
    // rays need no balance: a ray goes on in whichever level owns the next region
    if (seen === null) balanceAround(L, cx, cy, cz);
    split(L, c);
    return true;
  };

  // --- the queue: focused first, then (rays) more pixels hitting inside, then max priority, then nearer, then level, then chunk
  const qFocused: boolean[] = [];
  const qPixels: number[] = [];
  const qErr: number[] = [];
  const qDist: number[] = [];
  const qL: number[] = [];
  const qC: number[] = [];
  const heap: number[] = [];
  const before = (a: number, b: number): boolean =>
    qFocused[a] !== qFocused[b]
      ? qFocused[a]
      : qPixels[a] !== qPixels[b]
        ? qPixels[a] > qPixels[b]
        : qErr[a] !== qErr[b]
          ? qErr[a] > qErr[b]
          : qDist[a] !== qDist[b]
            ? qDist[a] < qDist[b]
            : qL[a] !== qL[b]
              ? qL[a] < qL[b]
              : qC[a] < qC[b];
  const push = (id: number): void => {
    let i = heap.length;
    heap.push(id);
    while (i > 0) {
      const p = (i - 1) >> 1;
      if (!before(id, heap[p])) break;
      heap[i] = heap[p];
      i = p;
    }
    heap[i] = id;
  };
  const pop = (): number => {
    const top = heap[0];
    const last = heap.pop()!;
    if (heap.length > 0) {
      let i = 0;
      const len = heap.length;
      for (;;) {
        const l = 2 * i + 1;
        if (l >= len) break;
        const r = l + 1;
        const m = r < len && before(heap[r], heap[l]) ? r : l;
        if (!before(heap[m], last)) break;
        heap[i] = heap[m];
        i = m;
      }
      heap[i] = last;
    }
    return top;
  };

  const wantsRanges = new Set<number>();
  /** Queues leaf (L, c) if it asks to be split. */
  const consider = (L: number, c: number): void => {
    if (L <= finest || k[L] === null) return;
    // a cut for rays refines only where the rays found the surface
    if (seen !== null && !seenIn(L, c)) return;
    const s = lv[L]!;
    const cx = c % s.gx;
    const cy = Math.floor(c / s.gx) % s.gy;
    const cz = Math.floor(c / (s.gx * s.gy));
    evalNode(L, cx, cy, cz);
    if (!nInView || !(nErr > tolerancePx)) return;
    if (needsOf(L - 1) === null) {
      wantsRanges.add(L - 1);
      return;
    }
    if (!canSplit(L, cx, cy, cz)) return;
    const id = qErr.length;
    qFocused.push(nFocused);
    qPixels.push(seen !== null ? seenOf(L).pixels[c] : 0);
    qErr.push(nPriority);
    qDist.push(nDist);
    qL.push(L);
    qC.push(c);
    push(id);
  };

  // --- roots
  const root = levelState(coarsest);
  if (root.need === null) wantsRanges.add(coarsest);
  const eR = E[coarsest];
  for (let z = 0; z < Math.min(root.gz, Math.ceil(Dz / eR[2])); z++)
    for (let y = 0; y < Math.min(root.gy, Math.ceil(Dy / eR[1])); y++)
      for (let x = 0; x < Math.min(root.gx, Math.ceil(Dx / eR[0])); x++) drawChild(root, x + root.gx * (y + root.gy * z));
  let limitedByBudget = false;
  if (bytes > budgetBytes) {
    limitedByBudget = true;
    notes.push(`the coarsest level's wanted chunks alone cost ${bytes} bytes, over the budget of ${budgetBytes}`);
  }
  for (let z = 0; z < root.gz; z++)
    for (let y = 0; y < root.gy; y++)
      for (let x = 0; x < root.gx; x++) {
        const c = x + root.gx * (y + root.gy * z);
        if (root.state[c] === LEAF) consider(coarsest, c);
      }

  // --- refine
  while (heap.length > 0) {
    const id = pop();
    const L = qL[id];
    const c = qC[id];
    const s = lv[L]!;
    if (s.state[c] !== LEAF) continue; // split already, by force (its children were considered then)
    const mark = logL.length;
    forceSplit(L, c);
    if (bytes > budgetBytes) {
      undoTo(mark);
      limitedByBudget = true;
      continue;
    }
    for (let i = mark; i < logL.length; i++) {
      const pl = logL[i];
      const cs = lv[pl - 1]!;
      forChildren(pl, logC[i], (_, child) => {
        if (cs.state[child] === LEAF) consider(pl - 1, child);
      });
    }
  }

  // --- the result: leaves level by level in chunk order, then nearest first (a stable sort keeps level, chunk)
  const sets: CutLevelSets[] = levels.map(() => ({ drawn: [], ghosts: [], wanted: [] }));
  for (let L = finest; L <= coarsest; L++) {
    const s = lv[L];
    if (!s || s.leaves === 0) continue;
    const { state } = s;
    const drawn = sets[L].drawn;
    for (let c = 0; c < state.length; c++) if (state[c] === LEAF || state[c] === PARTIAL) drawn.push(c);
  }
  const unsorted: CutNode[] = [];
  const dist: number[] = [];
  for (let L = finest; L <= coarsest; L++) {
    const s = lv[L];
    if (!s) continue;
    for (const c of sets[L].drawn) {
      const coords: [number, number, number] = [c % s.gx, Math.floor(c / s.gx) % s.gy, Math.floor(c / (s.gx * s.gy))];
      evalNode(L, coords[0], coords[1], coords[2]);
      unsorted.push({ level: L, chunk: c, coords, errorPx: nErr, distance: nDist, inView: nInView });
      dist.push(nDist);
    }
  }
  const order = unsorted.map((_, i) => i).sort((a, b) => dist[a] - dist[b]);
  const nodes = order.map((i) => unsorted[i]);

  let total = 0;
  for (let L = finest; L <= coarsest; L++) {
    const s = lv[L];
    const set = sets[L];
    if (!s || set.drawn.length === 0) continue;
    const { gx, gy, gz, state, need } = s;
    const seen = new Uint8Array(state.length);
    const sxy = gx * gy;
    const wanted: number[] = [];
    const wd: number[] = [];
    for (const d of set.drawn) {
      const cx = d % gx;
      const cy = Math.floor(d / gx) % gy;
      const cz = Math.floor(d / sxy);
      for (let dz = 0; dz < reach && cz + dz < gz; dz++)
        for (let dy = 0; dy < reach && cy + dy < gy; dy++)
          for (let dx = 0; dx < reach && cx + dx < gx; dx++) {
            const u = d + dx + dy * gx + dz * sxy;
            if (seen[u]) continue;
            seen[u] = 1;
            if (need !== null && !need(u)) continue;
            wanted.push(u);
            evalNode(L, cx + dx, cy + dy, cz + dz);
            wd.push(nDist);
            if (state[u] !== LEAF && state[u] !== PARTIAL) set.ghosts.push(u);
          }
    }
    set.ghosts.sort((a, b) => a - b);
    set.wanted = wanted
      .map((_, i) => i)
      .sort((a, b) => wd[a] - wd[b] || wanted[a] - wanted[b])
      .map((i) => wanted[i]);
    total += wanted.length * s.bytes;
  }

  return {
    nodes,
    levels: sets,
    bytes: total,
    nested: seen !== null,
    limitedByBudget,
    wantsRanges: [...wantsRanges].sort((a, b) => a - b),
    notes,
  };
}
