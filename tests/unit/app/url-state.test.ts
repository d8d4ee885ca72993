import { describe, expect, it } from 'vitest';
import { clipProblems, decodeViewState, encodeViewState } from '../../../src/app/url-state.ts';

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
  it('round-trips several surfaces: isovalues, opacity, colour, visibility and the selected one', () => {
    const hash = encodeViewState({
      iso: 120,
      selected: 1,
      surfaces: [
        { iso: 50.5, color: [1, 0, 0], opacity: 0.35, visible: true },
        { iso: 120, color: [0, 0.5, 1], opacity: 1, visible: false },
      ],
    });
    expect(hash).toBe('iso=50.5,120&op=0.35,1&col=ff0000,0080ff&vis=1,0&sel=1');
    const back = decodeViewState(`#${hash}`);
    expect(back.iso).toBe(120);
    expect(back.selected).toBe(1);
    expect(back.surfaces).toEqual([
      { iso: 50.5, color: [1, 0, 0], opacity: 0.35 },
      { iso: 120, color: [0, 128 / 255, 1], opacity: 1, visible: false },
    ]);
    // one surface: the one-value form, as before
    expect(encodeViewState({ iso: 3, surfaces: [{ iso: 3, opacity: 1 }] })).toBe('iso=3');
    expect(decodeViewState('#iso=3').surfaces).toBeUndefined();
    // malformed: a list with a non-number, more than 8, a selection out of range
    expect(decodeViewState('#iso=1,x')).toEqual({});
    expect(decodeViewState('#iso=1,2,3,4,5,6,7,8,9')).toEqual({});
    expect(decodeViewState('#iso=1,2&sel=5').selected).toBe(0);
  });
  it('round-trips the clip box and plane; refuses malformed ones', () => {
    const clip = { box: [1, 2, 3, 40, 50, 60] as const, plane: { normal: [0, 0.6, 0.8] as [number, number, number], d: 12.5 } };
    const hash = encodeViewState({ iso: 1, clip });
    expect(hash).toBe('iso=1&clip=1,2,3,40,50,60&plane=0,0.6,0.8,12.5');
    expect(decodeViewState(`#${hash}`).clip).toEqual(clip);
    expect(decodeViewState('#clip=5,0,0,1,1,1').clip).toBeUndefined(); // lower above upper
    expect(decodeViewState('#plane=0,0,0,4').clip).toBeUndefined(); // no direction
    expect(decodeViewState('#clip=0,0,0,1,1').clip).toBeUndefined();
    expect(clipProblems('#plane=0,0,0,4&clip=0,0,0,1,1')).toEqual([
      "The link's clip=0,0,0,1,1 is not a clip box (six numbers x0,y0,z0,x1,y1,z1); nothing is cut by it.",
      "The link's plane=0,0,0,4 is not a plane (the normal (nx, ny, nz) is zero: a plane needs a direction); nothing is cut by it.",
    ]);
    expect(clipProblems('#clip=0,0,0,1,1,1&plane=1,0,0,2')).toEqual([]);
  });
  it('keeps a plane turned by its knob (any unit normal) to 7 digits, and the same link again', () => {
    const n = [1, -2, 3].map((v) => v / Math.sqrt(14)) as [number, number, number];
    const hash = encodeViewState({ iso: 1, clip: { plane: { normal: n, d: 40.123456789 } } });
    expect(hash).toBe('iso=1&plane=0.2672612,-0.5345225,0.8017837,40.12346');
    const back = decodeViewState(`#${hash}`).clip!.plane!;
    back.normal.forEach((v, a) => expect(v).toBeCloseTo(n[a], 7));
    expect(back.d).toBeCloseTo(40.12346, 9);
    expect(encodeViewState({ iso: 1, clip: { plane: back } })).toBe(hash);
  });
  it('ignores malformed values', () => {
    expect(decodeViewState('#iso=abc&cam=1,2,3')).toEqual({});
    expect(decodeViewState('')).toEqual({});
  });
});
