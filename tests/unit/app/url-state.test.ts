import { describe, expect, it } from 'vitest';
import { decodeViewState, encodeViewState } from '../../../src/app/url-state.ts';

describe('view state in the URL hash', () => {
  it('round-trips isovalue and camera', () => {
    const s = {
      iso: 37.37,
      camera: {
        rotation: [0.1, 0.2, 0.3, 0.927] as [number, number, number, number],
        target: [1, 2, 3] as [number, number, number],
        distance: 250.5,
      },
    };
    const back = decodeViewState('#' + encodeViewState(s));
    expect(back.iso).toBeCloseTo(37.37, 5);
    expect(back.camera?.rotation[3]).toBeCloseTo(0.927, 6);
    expect(back.camera?.distance).toBeCloseTo(250.5, 4);
    expect(back.spacing).toBeUndefined();
  });
  it('round-trips a voxel size the user set', () => {
    const back = decodeViewState('#' + encodeViewState({ iso: 1, spacing: [0.5, 0.5, 2.25] }));
    expect(back.spacing).toEqual([0.5, 0.5, 2.25]);
    expect(decodeViewState('#vox=1,0,2').spacing).toBeUndefined();
    expect(decodeViewState('#vox=1,2').spacing).toBeUndefined();
  });
  it('ignores malformed values', () => {
    expect(decodeViewState('#iso=abc&cam=1,2,3')).toEqual({});
    expect(decodeViewState('')).toEqual({});
  });
});
