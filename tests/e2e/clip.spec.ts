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
import { nonBackgroundFraction, openApp, waitForFrames } from './page.ts';

interface Rec {
  clippedTriangles: number;
  area: number;
}

test('a clip box and a plane cut the surface, its exports and measures; a box outside the volume is refused', async ({
  page: cut,
  context,
}) => {
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
  const centre = vec4.transformMat4(vec4.create(), [32, 63.5, 63.5, 1], cam.viewProjection(mat4.create()));
  const rect = (await cut.locator('#view').boundingBox())!;
  const at = { x: rect.x + ((centre[0] / centre[3] + 1) / 2) * rect.width, y: rect.y + ((1 - centre[1] / centre[3]) / 2) * rect.height };
  await cut.mouse.move(at.x, at.y);
  await cut.keyboard.down('Control');
  await cut.mouse.down();
  await cut.mouse.move(at.x + 60, at.y + 30, { steps: 4 });
  await cut.mouse.up();
  await cut.keyboard.up('Control');
  const dragged = (await cut.evaluate(() => window.zfpiso!.clip))!.box!;
  expect(dragged.filter((v, i) => v !== [0, 0, 0, 64, 127, 127][i])).toHaveLength(1);
  expect(await cut.evaluate(() => window.zfpiso!.camera!())).toEqual(state.camera); // the camera did not turn

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
