import { describe, expect, it } from 'vitest';
import { computeBlockProfile } from '../../../src/app/ui/block-profile.ts';

describe('block profile', () => {
  it('counts, per bin centre, the blocks whose range contains it (brute force check)', () => {
    let seed = 1;
    const rnd = () => (seed = (seed * 1103515245 + 12345) % 2 ** 31) / 2 ** 31;
    const ranges = new Float32Array(2 * 500);
    for (let b = 0; b < 500; b++) {
      const a = rnd() * 100 - 10;
      ranges[2 * b] = a;
      ranges[2 * b + 1] = a + rnd() * 30;
    }
    const p = computeBlockProfile(ranges, 0, 100, 64);
    for (let i = 0; i < 64; i++) {
      const v = ((i + 0.5) / 64) * 100;
      let expected = 0;
      for (let b = 0; b < 500; b++) if (ranges[2 * b] <= v && v <= ranges[2 * b + 1]) expected++;
      expect(p.counts[i]).toBe(expected);
    }
  });
});
