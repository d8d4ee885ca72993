// Issue 47, "Series in": which dropped names read as a time series, and in
// which order (src/volume/series-names.ts).
import { describe, expect, it } from 'vitest';
import { seriesKindOf, seriesLabel, seriesOrder } from '../../../src/volume/series-names.ts';

const ordered = (names: string[]) => seriesOrder(names).order.map((i) => names[i]);

describe('series names', () => {
  it('orders numbered names by their number, not their text', () => {
    const names = [
      't10.tif',
      't2.tif',
      't1.tif',
      't12.tif',
      't11.tif',
      't3.tif',
      't4.tif',
      't5.tif',
      't6.tif',
      't7.tif',
      't8.tif',
      't9.tif',
    ];
    const s = seriesOrder(names);
    expect(s.sure).toBe(true);
    expect(ordered(names)).toEqual(Array.from({ length: 12 }, (_, i) => `t${i + 1}.tif`));
    expect(s.numbers).toEqual(Array.from({ length: 12 }, (_, i) => i + 1));
    // zero-padded and not alike: step_9 before step_010
    expect(ordered(['step_010.raw', 'step_9.raw', 'step_011.raw'])).toEqual(['step_9.raw', 'step_010.raw', 'step_011.raw']);
    expect(seriesOrder(['step_010.raw', 'step_9.raw', 'step_011.raw']).sure).toBe(true);
  });

  it('a shape in the names is not the number that counts the files', () => {
    const names = ['ball_3_48x48x48_uint8.raw', 'ball_1_48x48x48_uint8.raw', 'ball_2_48x48x48_uint8.raw'];
    expect(seriesOrder(names).sure).toBe(true);
    expect(ordered(names)).toEqual(['ball_1_48x48x48_uint8.raw', 'ball_2_48x48x48_uint8.raw', 'ball_3_48x48x48_uint8.raw']);
    // files of another shape stay in the series (to be refused for their shape, by name)
    const odd = ['ball_1_48x48x48_uint8.raw', 'ball_2_64x64x64_uint8.raw'];
    expect(seriesOrder(odd).sure).toBe(true);
  });

  it('evenly spaced numbers are sure (every 10th step dumped); gaps are not', () => {
    expect(seriesOrder(['out_0010.nrrd', 'out_0020.nrrd', 'out_0030.nrrd']).sure).toBe(true);
    const gaps = seriesOrder(['s_1.raw', 's_2.raw', 's_4.raw', 's_5.raw']);
    expect(gaps.sure).toBe(false);
    expect(gaps.why).toContain('gaps');
    expect(gaps.why).toContain('no 3');
    expect(gaps.numbers).toEqual([1, 2, 4, 5]);
  });

  it('two runs of numbers that differ, no numbers, names not alike, duplicates: not sure, with a natural order', () => {
    const two = seriesOrder(['r2_t1.raw', 'r1_t2.raw', 'r1_t1.raw']);
    expect(two.sure).toBe(false);
    expect(two.why).toContain('2 numbers');
    expect(two.order.map((i) => ['r2_t1.raw', 'r1_t2.raw', 'r1_t1.raw'][i])).toEqual(['r1_t1.raw', 'r1_t2.raw', 'r2_t1.raw']);
    const none = seriesOrder(['b.tif', 'a.tif', 'c.tif']);
    expect(none.sure).toBe(false);
    expect(none.order).toEqual([1, 0, 2]);
    expect(seriesOrder(['head.raw', 'tail7.raw']).sure).toBe(false);
    const dup = seriesOrder(['a_01.raw', 'a_1.raw', 'a_2.raw']);
    expect(dup.sure).toBe(false);
    expect(dup.why).toContain('more than one file has the number 1');
  });

  it('one kind of file only: mixed extensions and kinds a series is not made of give none', () => {
    expect(seriesKindOf(['a1.raw', 'a2.RAW'])).toBe('raw');
    expect(seriesKindOf(['a1.tif', 'a2.tiff'])).toBe('tiff');
    expect(seriesKindOf(['a1.nrrd', 'a2.nrrd'])).toBe('nrrd');
    expect(seriesKindOf(['a1.raw', 'a2.nrrd'])).toBeNull();
    expect(seriesKindOf(['a1.zfp', 'a2.zfp'])).toBeNull();
  });

  it('labels a series by its first and last file', () => {
    expect(seriesLabel(['step_000.raw', 'step_001.raw', 'step_019.raw'])).toBe('step_000.raw … step_019.raw (3 time points)');
  });
});
