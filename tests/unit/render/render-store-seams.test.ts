// The seams of a nested cut for rays (issue 46), against an analytic surface.
// A cut the rays refined where they hit is nested and has no ghosts: a finer
// level's rays stop at its chunk's last voxel, and the coarser level owning
// the next region traces those last cells from its own voxels (its chunk,
// drawn under the finer ones). A crack there would show background where
// the surface is. The field is linear (f = (x + 2y + 3z) / 6 in level-0
// voxels), so every level's averaged voxels sample the same plane and every
// level's isosurface is that plane: the image must be the plane on every
// pixel, whichever level draws it, with no background between levels.
// Checked: each pixel's hit distance against the ray's exact intersection
// with the plane, and every pixel whose ray meets the plane inside the
// volume (3 voxels in from its faces, where the coarser levels' boxes end
// earlier) covered. Without the coarser level's reach (the shader's seam
// below a region it owns) this image has 1511 such pixels of background.
// And a budget where the finer steps are refused: the coarse step on screen
// drawn whole (its caches computed again after the refused steps).
import { execFileSync, spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, it } from 'vitest';
import { repoRoot } from '../../helpers/python.ts';

const work = mkdtempSync(join(tmpdir(), 'render-seams-'));
const N = 128;
const raw = join(work, `plane_${N}x${N}x${N}_float32.raw`);
const store = join(work, 'plane.zarr');
// the plane x + 2y + 3z = 6 ISO, across the volume's middle (not a round number)
const ISO = 63.37;
const NORMAL = [1, 2, 3];
const [W, H] = [320, 200];

beforeAll(() => {
  const f = new Float32Array(N * N * N);
  for (let z = 0; z < N; z++) for (let y = 0; y < N; y++) for (let x = 0; x < N; x++) f[x + N * (y + N * z)] = (x + 2 * y + 3 * z) / 6;
  writeFileSync(raw, new Uint8Array(f.buffer));
  // rate 16: zfp keeps a linear field to ~1e-4 of a voxel here
  execFileSync(
    process.execPath,
    [join(repoRoot, 'scripts/convert.mjs'), raw, '--out', store, '--quiet', '--chunk', '16', '--rate', '16', '--levels', '3'],
    { cwd: repoRoot, stdio: 'pipe', timeout: 300_000 },
  );
}, 600_000);
afterAll(() => rmSync(work, { recursive: true, force: true }));

function render(budgetMb: number, ...more: string[]) {
  const name = `r${budgetMb}${more.join('')}`;
  const json = join(work, `${name}.json`);
  const depth = join(work, `${name}.f32`);
  const levels = join(work, `${name}.u8`);
  const r = spawnSync(
    process.execPath,
    [
      '--import',
      join(repoRoot, 'scripts/register-node-loaders.mjs'),
      join(repoRoot, 'src/cli/main.ts'),
      'render',
      store,
      '--iso',
      String(ISO),
      '--view-box',
      '0,0,0,80,80,80',
      '--cache-budget',
      String(budgetMb),
      '--size',
      `${W}x${H}`,
      '--png',
      join(work, `${name}.png`),
      '--depth',
      depth,
      '--json',
      json,
      '--level-map',
      levels,
      ...more,
    ],
    { encoding: 'utf8', timeout: 600_000 },
  );
  expect(r.status, r.stderr).toBe(0);
  return {
    record: JSON.parse(readFileSync(json, 'utf8')),
    depth: new Float32Array(new Uint8Array(readFileSync(depth)).buffer),
    levels: new Uint8Array(readFileSync(levels)),
  };
}

describe('rays over a nested cut: the seams between levels (an analytic plane)', () => {
  it('every pixel is the plane, whichever level draws it; no background between levels', () => {
    // 3 MB: the rays' cut draws levels 0, 1 and 2 side by side (nested, no ghosts)
    const { record, depth, levels } = render(3);
    expect(record.guided.passes).toBeGreaterThanOrEqual(1);
    expect(record.cut.every((l: { ghostChunks: number }) => l.ghostChunks === 0)).toBe(true);
    const shown = Object.entries(record.pixelsPerLevel as Record<string, number>).filter(([, n]) => n > 100);
    expect(shown.length).toBeGreaterThanOrEqual(2);
    expect(record.gpuPeakBytes).toBeLessThanOrEqual(3 * 2 ** 20);
    expectPlane(record, depth, levels);
  }, 900_000);

  it('a budget the finer steps do not fit: the rays draw the coarse step on screen whole, not the caches the refused step computed on', () => {
    // 2 MB: the view's cut wants levels 1 and 0, their surfaces do not fit, the stream stops on level 2's step; the
    // refused steps computed on level 2's cache in place, so the stream computes the step on screen again
    // (StoreStream.setKeepCaches: before, this image was empty)
    const { record, depth, levels } = render(2, '--no-guide');
    expect(record.cut.map((l: { level: number }) => l.level)).toEqual([2]);
    expectPlane(record, depth, levels);
  }, 900_000);
});

/**
 * Every pixel whose ray meets the plane inside the volume (3 voxels in from
 * its faces) is covered, and every covered pixel's hit distance is the
 * ray's exact intersection with the plane (voxel size 1, origin 0: world =
 * level-0 voxels), within zfp's error at rate 16.
 */
function expectPlane(record: { inverseViewProjection: number[]; eye: number[] }, depth: Float32Array, levels: Uint8Array): void {
  // each pixel's ray (voxel size 1, origin 0: world = level-0 voxels) and its exact hit on the plane
  const m = record.inverseViewProjection as number[];
  const eye = record.eye as number[];
  let inner = 0;
  let cracks = 0;
  let covered = 0;
  let worst = 0;
  for (let y = 0; y < H; y++)
    for (let x = 0; x < W; x++) {
      const i = y * W + x;
      const nx = ((x + 0.5) / W) * 2 - 1;
      const ny = 1 - ((y + 0.5) / H) * 2;
      const w = m[3] * nx + m[7] * ny + m[11] * 0.5 + m[15];
      const p = [0, 1, 2].map((a) => (m[a] * nx + m[4 + a] * ny + m[8 + a] * 0.5 + m[12 + a]) / w);
      const d = p.map((v, a) => v - eye[a]);
      const len = Math.hypot(d[0], d[1], d[2]);
      const dir = d.map((v) => v / len);
      const t = (6 * ISO - NORMAL.reduce((s, n, a) => s + n * eye[a], 0)) / NORMAL.reduce((s, n, a) => s + n * dir[a], 0);
      const hit = eye.map((e, a) => e + t * dir[a]);
      const inside = t > 0 && hit.every((v) => v > 3 && v < N - 4);
      if (inside) inner++;
      if (Number.isFinite(depth[i])) {
        covered++;
        expect(levels[i]).toBeLessThan(3);
        worst = Math.max(worst, Math.abs(depth[i] - t));
      } else if (inside) cracks++;
    }
  expect(inner).toBeGreaterThan(0.5 * W * H);
  expect(cracks).toBe(0);
  expect(covered).toBeGreaterThanOrEqual(inner);
  // the plane's crossing of every level's trilinear interpolant, within zfp's error at rate 16
  expect(worst).toBeLessThan(0.01);
}
