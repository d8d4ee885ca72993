// Cutting the surface open in the page: a clip box from the link draws less
// and exports exactly the CLI's clipped triangles (the unit tests hold the
// CLI's clip to VTK's vtkExtractVOI); the plane from the panel, stepped with
// the keys, measured as the CLI measures the same cut; the link keeps both;
// caps (unit-tested against NumPy) are drawn and can be turned off; a
// Ctrl-drag on the box moves the face under the pointer, not the camera;
// a clip box outside the volume is refused with a message and nothing cut.
import { readFileSync } from 'node:fs';
import { expect, test } from '@playwright/test';
import { mat4, vec4 } from 'gl-matrix';
import { parsePly } from '../../src/mc/ply.ts';
import { ArcballCamera } from '../../src/render/camera.ts';
import { runCli } from './cli.ts';
import { nonBackgroundFraction, openApp, waitForFrames, watchErrors } from './page.ts';

interface Rec {
  clippedTriangles: number;
  area: number;
}

test('a clip box and a plane cut the surface, its exports and measures; a box outside the volume is refused', async ({
  page: cut,
  context,
}) => {
  const errors = watchErrors(cut);
  await openApp(cut, '/#iso=0.43&clip=0,0,0,64,127,127');
  expect(await cut.evaluate(() => window.zfpiso!.clip)).toEqual({ box: [0, 0, 0, 64, 127, 127] });
  await expect(cut.locator('#clip-box-on')).toBeChecked();
  // the caps: the blocks along the box's faces decoded, drawn where the cut is inside the surface
  expect(await cut.evaluate(() => window.zfpiso!.capBlocks)).toBeGreaterThan(0);
  await waitForFrames(cut, 2);
  const withCaps = await cut.locator('#view').screenshot();
  await cut.locator('#clip-caps').uncheck();
  await waitForFrames(cut, 2);
  expect(Buffer.compare(await cut.locator('#view').screenshot(), withCaps)).not.toBe(0);
  // without caps, less of the surface is drawn than uncut
  const cutOpen = await nonBackgroundFraction(cut);
  await cut.locator('#clip-box-on').uncheck();
  await waitForFrames(cut, 2);
  expect(cutOpen).toBeLessThan((await nonBackgroundFraction(cut)) * 0.8);
  await cut.locator('#clip-box-on').check();
  await cut.locator('#clip-caps').check();
  const [box] = (await runCli<{ isosurfaces: Rec[] }>(['extract', 'default', '--iso', '0.43', '--clip', '0,0,0,64,127,127'])).isosurfaces;
  const [ply] = await Promise.all([cut.waitForEvent('download'), cut.locator('#save-ply').click()]);
  const mesh = parsePly(new Uint8Array(readFileSync((await ply.path())!)));
  expect(mesh.indices.length / 3).toBe(box.clippedTriangles);

  // Ctrl-drag on the box: the face under the pointer follows it (one coordinate of the box changes)
  const state = await cut.evaluate(() => ({
    camera: window.zfpiso!.camera!(),
    size: [document.querySelector('canvas')!.width, document.querySelector('canvas')!.height],
  }));
  const cam = new ArcballCamera();
  cam.setState(state.camera);
  cam.aspect = state.size[0] / state.size[1];
  const rect = (await cut.locator('#view').boundingBox())!;
  /** A voxel's place on the page (voxel size 1, origin 0: the built-in volume). */
  const onPage = (p: readonly number[]) => {
    const c = vec4.transformMat4(vec4.create(), [p[0], p[1], p[2], 1], cam.viewProjection(mat4.create()));
    return { x: rect.x + ((c[0] / c[3] + 1) / 2) * rect.width, y: rect.y + ((1 - c[1] / c[3]) / 2) * rect.height };
  };
  /** A drag of `by` page pixels along the screen direction of voxel direction `dir` at p, starting at p. */
  const dragAlong = async (p: readonly number[], dir: readonly number[], by: number) => {
    const a = onPage(p),
      b = onPage(p.map((v, k) => v + dir[k]));
    const len = Math.hypot(b.x - a.x, b.y - a.y);
    await cut.mouse.move(a.x, a.y);
    await cut.mouse.down();
    await cut.mouse.move(a.x + ((b.x - a.x) / len) * by, a.y + ((b.y - a.y) / len) * by, { steps: 4 });
    await cut.mouse.up();
  };
  const at = onPage([32, 63.5, 63.5]);
  await cut.mouse.move(at.x, at.y);
  await cut.keyboard.down('Control');
  await cut.mouse.down();
  await cut.mouse.move(at.x + 60, at.y + 30, { steps: 4 });
  await cut.mouse.up();
  await cut.keyboard.up('Control');
  const dragged = (await cut.evaluate(() => window.zfpiso!.clip))!.box!;
  expect(dragged.filter((v, i) => v !== [0, 0, 0, 64, 127, 127][i])).toHaveLength(1);
  expect(await cut.evaluate(() => window.zfpiso!.camera!())).toEqual(state.camera); // the camera did not turn

  // a plain drag from the upper x face's handle (the disc at its centre; hovering it shows a grab cursor):
  // that face moves in, in whole voxels, and the link follows; the camera stays
  const face = [dragged[3], (dragged[1] + dragged[4]) / 2, (dragged[2] + dragged[5]) / 2];
  const handle = onPage(face);
  await cut.mouse.move(handle.x, handle.y);
  await expect.poll(() => cut.locator('#view').evaluate((e) => (e as HTMLElement).style.cursor)).toBe('grab');
  await dragAlong(face, [-1, 0, 0], 40);
  const moved = (await cut.evaluate(() => window.zfpiso!.clip))!.box!;
  expect(moved[3]).toBeLessThan(dragged[3]);
  expect(Number.isInteger(moved[3])).toBe(true);
  expect(moved.filter((v, i) => i !== 3 && v !== dragged[i])).toHaveLength(0);
  await cut.waitForFunction((box) => location.hash.includes(`clip=${box}`), moved.join(','));
  expect(await cut.evaluate(() => window.zfpiso!.camera!())).toEqual(state.camera);

  // the plane: normal z at 40, stepped twice with '.', then Shift+',' (-10): z >= 32
  await cut.locator('#clip-box-on').uncheck();
  await cut.locator('#clip-plane-axis').selectOption('z');
  await cut.locator('#clip-plane-offset').fill('40');
  await cut.locator('body').press('.');
  await cut.locator('body').press('.');
  await cut.locator('body').press('Shift+<');
  await expect.poll(() => cut.evaluate(() => window.zfpiso!.clip)).toEqual({ plane: { normal: [0, 0, 1], d: 32 } });
  await cut.waitForFunction(() => location.hash.includes('plane=0,0,1,32') && !location.hash.includes('clip='));
  const [plane] = (await runCli<{ isosurfaces: Rec[] }>(['extract', 'default', '--iso', '0.43', '--plane', '0,0,1,32'])).isosurfaces;
  await cut.locator('#measure-surface').click();
  await cut.waitForFunction(() => window.zfpiso!.measure !== undefined);
  const m = (await cut.evaluate(() => window.zfpiso!.measure))!;
  expect(m.triangles).toBe(plane.clippedTriangles);
  expect(m.area).toBeCloseTo(plane.area, 6);
  expect(m.enclosedVolume).toBeNull();

  // the plane's handles: its centre (the middle of its polygon in the volume) moves it along its normal,
  // its knob (a stick of 0.18 of the volume's diagonal along the normal) turns it about the centre
  const centre = [63.5, 63.5, 32];
  await dragAlong(centre, [0, 0, 1], 30);
  const along = (await cut.evaluate(() => window.zfpiso!.clip))!.plane!;
  expect(along.normal).toEqual([0, 0, 1]);
  expect(along.d).toBeGreaterThan(33);
  centre[2] = along.d;
  const knob = [centre[0], centre[1], centre[2] + 0.18 * 127 * Math.sqrt(3)];
  await dragAlong(knob, [1, 0, 0], 40);
  const turned = (await cut.evaluate(() => window.zfpiso!.clip))!.plane!;
  expect(Math.hypot(...turned.normal)).toBeCloseTo(1, 9);
  expect(turned.normal.filter((v) => Math.abs(v) > 0.05).length).toBeGreaterThanOrEqual(2);
  expect(turned.normal[2]).toBeGreaterThan(0.5); // turned, not flipped
  // the centre stayed on the plane
  expect(turned.normal[0] * centre[0] + turned.normal[1] * centre[1] + turned.normal[2] * centre[2]).toBeCloseTo(turned.d, 4);
  await cut.waitForFunction((n) => location.hash.includes(`plane=${n}`), turned.normal.map((v) => Number(v.toPrecision(7))).join(','));
  // the panel shows the normal (url-state.test.ts: the link's plane= gives it back)
  await expect(cut.locator('#clip-plane-normal')).toHaveValue(turned.normal.map((v) => Number(v.toFixed(4))).join(', '));
  await expect(cut.locator('#clip-plane-axis')).toHaveValue('free');
  // ',' still steps it along its (new) normal
  await cut.locator('body').press(',');
  await expect.poll(async () => (await cut.evaluate(() => window.zfpiso!.clip))!.plane!.d).toBeCloseTo(turned.d - 1, 6);
  expect(errors).toEqual([]);

  // a box that holds no cell: a message, nothing cut
  // a box that holds no cell, and (surfaces.ts) an isovalue outside the values: a message each, nothing cut,
  // the surfaces that could be made
  const bad = await context.newPage();
  await openApp(bad, '/#iso=0.43,99&clip=200,0,0,300,10,10');
  await expect(bad.locator('#messages')).toContainText('Clip box 200,0,0,300,10,10: the box holds no cell of the volume');
  expect(await bad.evaluate(() => window.zfpiso!.clip)).toBeUndefined();
  await expect(bad.locator('#messages')).toContainText('Isovalue 99 is outside the volume');
  expect((await bad.evaluate(() => window.zfpiso!.surfaces!)).entries.map((e) => e.iso)).toEqual([0.43]);
});
