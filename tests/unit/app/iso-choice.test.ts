import { describe, expect, it } from 'vitest';
import { blockMidpoints, chooseIsovalue, otsuThreshold } from '../../../src/app/iso-choice.ts';

describe('starting isovalue', () => {
  it('Otsu splits two clusters between them', () => {
    const values = [...Array.from({ length: 900 }, (_, i) => 10 + (i % 7)), ...Array.from({ length: 100 }, (_, i) => 200 + (i % 11))];
    const t = otsuThreshold(values, 0, 255);
    expect(t).toBeGreaterThan(17);
    expect(t).toBeLessThan(200);
  });

  it('ignores constant blocks and stays inside the range', () => {
    // 1000 constant background blocks, 50 blocks crossing 0..100, 50 around 100..140
    const r: number[] = [];
    for (let i = 0; i < 1000; i++) r.push(0, 0);
    for (let i = 0; i < 50; i++) r.push(0, 100);
    for (let i = 0; i < 50; i++) r.push(100, 140);
    const ranges = new Float32Array(r);
    expect(blockMidpoints(ranges).length).toBe(100);
    const iso = chooseIsovalue(ranges, [0, 140]);
    expect(iso).toBeGreaterThan(50);
    expect(iso).toBeLessThan(120);
  });

  it('copes with a constant volume', () => {
    const iso = chooseIsovalue(new Float32Array([3, 3, 3, 3]), [3, 3]);
    expect(Number.isFinite(iso)).toBe(true);
  });
});
