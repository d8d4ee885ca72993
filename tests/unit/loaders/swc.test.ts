// SWC parser against the Python SWC reader's figures (shared expected.json).
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { describe, expect, test } from 'vitest';
import { parseSwc, SwcError, swcStats, swcTypeColor, swcTypeName } from '../../../src/loaders/swc.ts';
import { sharedData, sharedExpected } from './fixtures.ts';

const expected = sharedExpected('swc');

describe('shared SWC files match the Python reader (expected.json)', () => {
  test.each(Object.keys(expected))('%s', (name) => {
    const e = expected[name];
    const tree = parseSwc(readFileSync(join(sharedData, 'swc', name), 'utf8'), name);
    const s = swcStats(tree);
    expect(s.sampleCount).toBe(e.sample_count);
    expect(s.rootCount).toBe(e.root_count);
    expect(s.rootIds).toEqual(e.root_ids);
    expect(s.orphanParentCount).toBe(e.orphan_parent_count);
    expect(s.duplicateIds).toBe(e.duplicate_ids);
    expect(s.typeCounts).toEqual(e.type_counts);
    expect(s.bbox).toEqual(e.bbox);
    for (const k of ['min', 'max'] as const)
      for (let a = 0; a < 3; a++) expect(s.bboxWithRadius[k][a]).toBeCloseTo(e.bbox_with_radius[k][a], 10);
    // Same float64 sum in the same (file) order: equal to the last bit.
    expect(s.totalCableLength).toBe(e.total_cable_length);
    expect(s.segmentCount).toBe(e.segment_count);
    expect(s.branchPoints).toBe(e.branch_points);
    expect(s.tips).toBe(e.tips);
    expect(s.radiusMinMax).toEqual(e.radius_min_max);
    expect(tree.comments.length).toBeGreaterThan(0);
  });
});

describe('real-world SWC variations', () => {
  test('type codes 0-7 and above, tabs, CRLF, float-formatted ids, extra columns', () => {
    const text = [
      '# made by a tracing tool',
      '1\t1\t0 0 0 5 -1',
      '2 0 1 0 0 1 1',
      '3 5 2 0 0 1 2 extra-column',
      '4 6 3 0 0 1 3',
      '5.0 7 3 1 0 1 4.0',
      '6 12 3 2 0 1 5',
      '7 255 3 3 0 0.5 6',
      '',
    ].join('\r\n');
    const tree = parseSwc(text, 'custom.swc');
    expect(tree.count).toBe(7);
    expect([...tree.types]).toEqual([1, 0, 5, 6, 7, 12, 255]);
    expect([...tree.parentIndex]).toEqual([-1, 0, 1, 2, 3, 4, 5]);
    const s = swcStats(tree);
    expect(s.typeCounts).toEqual({ '0': 1, '1': 1, '5': 1, '6': 1, '7': 1, '12': 1, '255': 1 });
    expect(s.totalCableLength).toBe(6);
    expect(swcTypeName(2)).toBe('axon');
    expect(swcTypeName(12)).toBe('custom 12');
    // Custom codes get distinct, visible colours.
    const c12 = swcTypeColor(12);
    const c13 = swcTypeColor(13);
    expect(c12).not.toEqual(c13);
    for (const c of [...c12, ...c13]) expect(c).toBeGreaterThanOrEqual(0.35);
  });

  test('missing parents and several roots are kept, not fatal', () => {
    const tree = parseSwc('1 1 0 0 0 1 -1\n2 3 1 0 0 1 1\n3 3 5 5 5 1 99\n4 2 0 0 1 1 -1\n', 'pieces.swc');
    const s = swcStats(tree);
    expect(s.rootCount).toBe(2);
    expect(s.orphanParentCount).toBe(1);
    expect(tree.parentIndex[2]).toBe(-1);
    expect(s.segmentCount).toBe(1);
  });

  test('malformed lines name the file and line', () => {
    expect(() => parseSwc('# header\n1 1 0 0 0 1 -1\n2 3 0 0\n', 'short.swc')).toThrow(
      /^short\.swc, line 3: expected 7 columns \(id type x y z radius parent\), found 4/,
    );
    expect(() => parseSwc('1 1 0 0 zero 1 -1\n', 'nan.swc')).toThrow(/^nan\.swc, line 1: z "zero" is not a number/);
    expect(() => parseSwc('1.5 1 0 0 0 1 -1\n', 'id.swc')).toThrow(/^id\.swc, line 1: id "1.5" is not an integer/);
    expect(() => parseSwc('# only comments\n\n', 'empty.swc')).toThrow(SwcError);
    expect(() => parseSwc('\u0000\u0001binary junk', 'junk.swc')).toThrow(/^junk\.swc, line 1: expected 7 columns/);
  });
});
