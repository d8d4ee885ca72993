// `cli render STORE` (issue 46): a store refined by the image's view, ray
// cast over its multi-resolution bricks (each level's pool and cache, only
// over the chunks it draws) against its mesh, same view, same cut
// (--mesh-cut). A generated store zoomed into its lower corner within a
// budget that makes the cut mix levels 0, 1 and 2 on screen:
//   - coverage IoU >= 0.99 and, where both hit, depth within one voxel of
//     the level the pixel shows on >= 99% of the pixels (the mesh itself is
//     checked against VTK in tests/unit/store/view-cut-cli.test.ts);
//   - the seams: not one pixel of background in the ray image inside the
//     mesh's surface (a pixel whose 3x3 neighbourhood the mesh covers).
//     Without the rays' reach above a level's drawn chunks the coarser
//     level's offset leaves a crack there (hundreds of such pixels at this
//     view: checked when the reach was written);
//   - the record: which level each pixel shows, level 0's share, within the budget;
//   - rays by default hold no vertices (surfaces of block caches only): at
//     the same budget and view their cut is finer, and within the budget.
import { spawnSync } from 'node:child_process';
import { existsSync, mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, it } from 'vitest';
import { repoRoot } from '../../helpers/python.ts';
import { convert } from '../store/stores.ts';

const work = mkdtempSync(join(tmpdir(), 'render-store-'));
const store = join(work, 'gen256.zarr');
// not a round number (no voxel exactly at it)
const ISO = 0.437;
const BOX = '0,0,0,60,60,60';
const BUDGET_MB = 16;
const [W, H] = [480, 300];

beforeAll(() => {
  convert('gen:256x256x256', store, ['--chunk', '32', '--rate', '8', '--levels', '4']);
}, 900_000);
afterAll(() => rmSync(work, { recursive: true, force: true }));

function render(draw: 'rays' | 'mesh', ...more: string[]) {
  const name = `${draw}${more.join('')}`;
  const json = join(work, `${name}.json`);
  const depth = join(work, `${name}.f32`);
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
      '--draw',
      draw,
      '--view-box',
      BOX,
      '--cache-budget',
      String(BUDGET_MB),
      '--size',
      `${W}x${H}`,
      '--png',
      join(work, `${name}.png`),
      '--depth',
      depth,
      '--json',
      json,
      '--level-map',
      join(work, `${name}.u8`),
      ...more,
    ],
    { encoding: 'utf8', timeout: 600_000 },
  );
  expect(r.status, r.stderr).toBe(0);
  return {
    record: JSON.parse(readFileSync(json, 'utf8')),
    depth: new Float32Array(new Uint8Array(readFileSync(depth)).buffer),
  };
}

describe('cli render STORE', () => {
  it('rays over mixed levels: the mesh image within a voxel, no background at the seams, the levels per pixel, within the budget', () => {
    const rays = render('rays', '--mesh-cut');
    const mesh = render('mesh');
    for (const r of [rays, mesh]) {
      // the cut mixes levels on screen, level 0 where the box is
      expect(r.record.levels).toEqual([0, 1, 2]);
      expect(Object.keys(r.record.pixelsPerLevel).length).toBeGreaterThanOrEqual(2);
      expect(r.record.level0Fraction).toBeGreaterThan(0.1);
      expect(r.record.gpuPeakBytes).toBeLessThanOrEqual(BUDGET_MB * 2 ** 20);
    }
    // the same cut either way
    expect(rays.record.cut.map((l: { level: number; drawnChunks: number }) => [l.level, l.drawnChunks])).toEqual(
      mesh.record.cut.map((l: { level: number; drawnChunks: number }) => [l.level, l.drawnChunks]),
    );
    expect(rays.record.triangles).toBe(0);
    // which level each pixel shows (the mesh's record, the same cut): the depth's tolerance there
    const levelAt = new Uint8Array(readFileSync(join(work, 'mesh.u8')));
    expect(levelAt.length).toBe(W * H);

    let union = 0;
    let both = 0;
    let within = 0;
    let holes = 0;
    const hit = (d: Float32Array, i: number) => Number.isFinite(d[i]);
    for (let y = 0; y < H; y++) {
      for (let x = 0; x < W; x++) {
        const i = y * W + x;
        const r = hit(rays.depth, i);
        const m = hit(mesh.depth, i);
        if (r || m) union++;
        if (r && m) {
          both++;
          if (Math.abs(rays.depth[i] - mesh.depth[i]) <= 2 ** levelAt[i]) within++;
        }
        if (!r && m && x > 0 && y > 0 && x < W - 1 && y < H - 1) {
          let inside = true;
          for (let dy = -1; dy <= 1 && inside; dy++) for (let dx = -1; dx <= 1; dx++) inside &&= hit(mesh.depth, i + dy * W + dx);
          if (inside) holes++;
        }
      }
    }
    expect(both).toBeGreaterThan(0.3 * W * H);
    expect(both / union).toBeGreaterThanOrEqual(0.99);
    expect(within / both).toBeGreaterThanOrEqual(0.99);
    expect(holes).toBe(0);
    // each level's share of the screen agrees with the mesh's (within 2% of the covered pixels)
    for (const L of Object.keys(mesh.record.pixelsPerLevel)) {
      expect(Math.abs((rays.record.pixelsPerLevel[L] ?? 0) - mesh.record.pixelsPerLevel[L])).toBeLessThanOrEqual(0.02 * both);
    }
  }, 900_000);

  it('rays by default: surfaces of block caches only, so at the same budget the cut holds more fine chunks, within the budget', () => {
    const rays = render('rays');
    // the first test's mesh record (made here when that test was not run)
    const mesh = existsSync(join(work, 'mesh.json')) ? JSON.parse(readFileSync(join(work, 'mesh.json'), 'utf8')) : render('mesh').record;
    const fine = (r: { cut: { level: number; drawnChunks: number }[] }) =>
      r.cut.filter((l) => l.level <= 1).reduce((a, l) => a + l.drawnChunks * 8 ** (1 - l.level), 0);
    // level-0 chunks, counting a level-1 chunk as the 8 it would be
    expect(fine(rays.record)).toBeGreaterThan(fine(mesh));
    expect(rays.record.cut.every((l: { triangles: number }) => l.triangles === 0)).toBe(true);
    expect(rays.record.gpuPeakBytes).toBeLessThanOrEqual(BUDGET_MB * 2 ** 20);
    expect(rays.record.coveredPixels).toBeGreaterThan(0.3 * W * H);
  }, 900_000);
});
