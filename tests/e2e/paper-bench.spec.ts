// The benchmark page (paper-bench.html): the form runs every method on a
// shared volume and shows a row each, all methods agreeing on the triangles;
// the API that `npm run bench:paper` drives gives VTK's triangle counts for
// the serial MC (JS and Wasm) and the naive WebGPU MC, and decodes zfp with
// zfp's C decoder in Wasm; a missing volume is reported, not hung on.
import { readFileSync } from 'node:fs';
import { fileURLToPath } from 'node:url';
import { expect, test } from '@playwright/test';
import { openApp, watchErrors } from './page.ts';

interface McEntry {
  file: string;
  dims_xyz: [number, number, number];
  isosurfaces: { iso: number; vtkMarchingCubes: { triangles: number } }[];
}
const mc = JSON.parse(readFileSync(fileURLToPath(new URL('../../../shared/data/reference/mc.json', import.meta.url)), 'utf8')) as {
  volumes: McEntry[];
};
const entry = (file: string) => mc.volumes.find((v) => v.file === file)!;

test('the form runs every method on the fuel volume; they agree on the triangles', async ({ page }) => {
  const errors = watchErrors(page);
  await openApp(page, '/paper-bench.html');
  await page.selectOption('#volume', '/data/volumes/fuel_64x64x64_float32.raw');
  await page.fill('#count', '4');
  await page.fill('#runs', '2');
  await page.click('#run');
  await expect(page.locator('#status')).toHaveText('done', { timeout: 170_000 });
  const rows = page.locator('#results tbody tr');
  await expect(rows).toHaveCount(6);
  const labels = await rows.locator('td:first-child').allTextContents();
  expect(labels[0]).toBe('serial MC, JavaScript');
  expect(labels[1]).toBe('serial MC, WebAssembly');
  expect(labels[2]).toContain('zfp decode');
  expect(labels[3]).toContain('zfp decode, WebGPU');
  expect(labels[4]).toContain('naive MC, WebGPU');
  // Mean triangles (column 5) of the serial JS, serial Wasm and naive GPU rows are equal and not zero.
  const triangles = await Promise.all([0, 1, 4].map((i) => rows.nth(i).locator('td').nth(4).textContent()));
  expect(Number(triangles[0]!.replace(/,/g, ''))).toBeGreaterThan(0);
  expect(new Set(triangles).size).toBe(1);
  await expect(page.locator('#results-note')).toContainText('fuel_64x64x64_float32.rate8.zfp');
  expect(errors).toEqual([]);
});

test("the API: serial MC (JS, Wasm) and naive WebGPU MC give VTK's triangle counts; zfp Wasm decodes", async ({ page }) => {
  const errors = watchErrors(page);
  await openApp(page, '/paper-bench.html');
  const fuel = entry('volumes/fuel_64x64x64_float32.raw');
  const isovalues = fuel.isosurfaces.map((s) => s.iso);
  const serial = await page.evaluate(
    (a) =>
      window.paperBench!.serialMc({
        url: '/data/volumes/fuel_64x64x64_float32.raw',
        dims: a.dims,
        isovalues: a.isovalues,
        methods: ['js', 'wasm'],
      }),
    { dims: fuel.dims_xyz, isovalues },
  );
  const vtk = fuel.isosurfaces.map((s) => s.vtkMarchingCubes.triangles);
  expect(serial.js!.triangles).toEqual(vtk);
  expect(serial.wasm!.triangles).toEqual(vtk);
  expect(serial.js!.ms.every((x) => x >= 0)).toBe(true);

  const hydrogen = entry('volumes/hydrogen_atom_128x128x128_float32.rate8.zfp');
  const url = '/data/volumes/hydrogen_atom_128x128x128_float32.rate8.zfp';
  const naive = await page.evaluate((a) => window.paperBench!.naiveMc({ url: a.url, isovalues: a.isovalues }), {
    url,
    isovalues: hydrogen.isosurfaces.slice(0, 3).map((s) => s.iso),
  });
  expect(naive.triangles).toEqual(hydrogen.isosurfaces.slice(0, 3).map((s) => s.vtkMarchingCubes.triangles));
  expect(naive.adapter).toMatch(/swiftshader/i);

  const decoded = await page.evaluate((u) => window.paperBench!.zfpWasm({ url: u, runs: 2 }), url);
  expect(decoded.dims).toEqual([128, 128, 128]);
  expect(decoded.floatBytes).toBe(128 ** 3 * 4);
  expect(decoded.ms).toHaveLength(2);
  const gpu = await page.evaluate((u) => window.paperBench!.gpuDecode({ url: u, runs: 2 }), url);
  expect(gpu.ms).toHaveLength(2);
  expect(errors).toEqual([]);
});

test('a volume that is not there is an error with its name', async ({ page }) => {
  await openApp(page, '/paper-bench.html');
  const message = await page.evaluate(() =>
    window.paperBench!.zfpWasm({ url: '/data/volumes/nothing.zfp', runs: 2 }).then(
      () => 'resolved',
      (e: Error) => e.message,
    ),
  );
  expect(message).toContain('/data/volumes/nothing.zfp: HTTP 404');
});
