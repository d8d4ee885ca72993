// The bricks a store's rate is chosen from (src/store/zarr/open-source.ts
// spreadBricks): spread over the level in 3-D, so a specimen in the middle of
// empty space is sampled. Evenly spaced brick indices were not: 32 of a 16^3
// grid all lay on the face x = 0, and a centred ball got rate 1.
import { describe, expect, it } from 'vitest';
import { spreadBricks } from '../../../src/store/zarr/open-source.ts';

const coords = (grid: [number, number, number], b: number) => [
  b % grid[0],
  Math.floor(b / grid[0]) % grid[1],
  Math.floor(b / (grid[0] * grid[1])),
];

describe('spreadBricks', () => {
  it('32 of 16^3: a 3^3 lattice through the middle of every axis, the centre brick among them', () => {
    const grid: [number, number, number] = [16, 16, 16];
    const picks = spreadBricks(grid, 32);
    expect(picks.length).toBe(27);
    for (let a = 0; a < 3; a++) expect(new Set(picks.map((b) => coords(grid, b)[a]))).toEqual(new Set([2, 8, 13]));
    expect(picks).toContain(8 + 16 * (8 + 16 * 8));
  });

  it('awkward grids: within k, distinct, inside the grid, every axis spread as far as k allows', () => {
    const cases: [[number, number, number], number][] = [
      [[1, 1, 1], 64],
      [[80, 2, 2], 32],
      [[3, 1, 200], 64],
      [[5, 7, 9], 64],
      [[64, 64, 64], 1],
      [[2, 2, 2], 64],
    ];
    for (const [grid, k] of cases) {
      const picks = spreadBricks(grid, k);
      const n = grid[0] * grid[1] * grid[2];
      expect(picks.length, `${grid} ${k}`).toBeLessThanOrEqual(Math.min(k, n));
      expect(picks.length).toBeGreaterThan(0);
      expect(new Set(picks).size).toBe(picks.length);
      for (const b of picks) expect(b >= 0 && b < n).toBe(true);
      // an axis is left unspread only when spreading it further would pass k
      const spread = [0, 1, 2].map((a) => new Set(picks.map((b) => coords(grid, b)[a])).size);
      const m = Math.max(...spread);
      for (let a = 0; a < 3; a++) expect(spread[a]).toBe(Math.min(grid[a], m));
    }
    expect(spreadBricks([80, 2, 2], 32).length).toBe(32);
    expect(spreadBricks([2, 2, 2], 64).length).toBe(8);
  });
});
