// Stores written by ngff-zarr (issue 37: the library that writes the OME-Zarr
// Open SciVis collection), from volumes in ../shared/data
// (tests/fixtures/ngff-stores.py, ngff-zarr 0.50.0 pinned): OME 0.4 / Zarr
// v2 in chunks of 96, OME 0.5 / Zarr v3 sharded 2 chunks per shard, the same
// zipped (.ozx, RFC 9) read in place as a file and over HTTP, and an int16
// pyramid whose level 1 halves only z (drawn where its scale puts it; level 1
// = zarr-python's array of it in core). Truth from outside: level 0 at rate 8
// = the raw file in core at rate 8, the same triangles (NumPy over both PLY
// files); at the rate chosen from the data, within 1% of vtkMarchingCubes
// (shared/data/reference/mc.json); zip files damaged in each way we read
// them are refused by name.
import { execFileSync } from 'node:child_process';
import { mkdirSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { createServer, type Server } from 'node:http';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, it } from 'vitest';
import { storesMiddleware } from '../../../scripts/vite-stores.ts';
import { storeForLocation } from '../../../src/store/zarr/node-store.ts';
import { openStore } from '../../../src/store/zarr/open-store.ts';
import { repoRoot, sharedData } from '../../helpers/python.ts';
import { cli, converterPython, samePly } from './stores.ts';

const work = mkdtempSync(join(tmpdir(), 'ngff-stores-'));
interface Entry {
  store: string;
  raw: string;
  levels: number;
  dtype: string;
  shapes?: number[][];
}
let manifest: Record<string, Entry>;
let server: Server;
let base = '';

beforeAll(async () => {
  const out = execFileSync(
    join(repoRoot, '.venv-converter/bin/python'),
    [join(repoRoot, 'tests/fixtures/ngff-stores.py'), join(work, 'stores'), join(sharedData, 'volumes')],
    { encoding: 'utf8', timeout: 600_000, stdio: ['ignore', 'pipe', 'ignore'] },
  );
  manifest = JSON.parse(out);
  const mw = storesMiddleware(join(work, 'stores'));
  server = createServer((req, res) =>
    mw(req, res, () => {
      res.statusCode = 404;
      res.end();
    }),
  );
  await new Promise<void>((r) => server.listen(0, '127.0.0.1', () => r()));
  const a = server.address();
  base = `http://127.0.0.1:${typeof a === 'object' && a ? a.port : 0}`;
}, 600_000);
afterAll(() => {
  server?.close();
  rmSync(work, { recursive: true, force: true });
});

function extract(input: string, iso: number[], prefix: string, extra: string[] = []) {
  const json = `${prefix}.json`;
  const r = cli('extract', input, `--iso=${iso.join(',')}`, '--ply', prefix, '--json', json, ...extra);
  expect(r.status, r.stderr).toBe(0);
  return { record: JSON.parse(readFileSync(json, 'utf8')), stderr: r.stderr };
}

const triangles = (r: { isosurfaces: { triangles: number }[] }) => r.isosurfaces.map((x) => x.triangles);

/** Both stores open alike (rate 8) and every brick of every level decodes to the same bytes. */
async function expectSameBricks(location: string, reference: string): Promise<void> {
  const [a, b] = await Promise.all([location, reference].map((l) => openStore(storeForLocation(l), l, { rate: 8 })));
  try {
    expect(a.levels.map((l) => [l.path, ...l.layout.dims])).toEqual(b.levels.map((l) => [l.path, ...l.layout.dims]));
    for (const lv of b.levels)
      for (let c = 0; c < lv.chunkCount; c++) {
        const [x, y] = await Promise.all([a.readChunk(lv.index, c), b.readChunk(lv.index, c)]);
        expect(Buffer.from(x).equals(Buffer.from(y)), `${location} level ${lv.index} brick ${c}`).toBe(true);
      }
  } finally {
    a.close?.();
    b.close?.();
  }
}

describe('stores written by ngff-zarr', () => {
  for (const [key, iso, codec] of [
    ['neghip_v04', [80.5, 140.5], /Zarr v2 store of uint8 \(zstd\)/],
    ['neghip_v05', [80.5, 140.5], /Zarr v3 store of uint8 \(sharding_indexed\(bytes, zstd\)\)/],
    ['neghip_ozx', [80.5, 140.5], /Zarr v3 store of uint8 \(sharding_indexed\(bytes, zstd\)\)/],
    ['hydrogen_aniso', [1500.5, 4000.5], /Zarr v3 store of int16 \(sharding_indexed\(bytes, zstd\)\)/],
  ] as const) {
    it(`${key}: level 0 at rate 8 = the raw volume in core at rate 8, triangle for triangle`, () => {
      const m = manifest[key];
      const s = extract(m.store, [...iso], join(work, `${key}-store`), ['--level', '0', '--rate', '8']);
      const c = extract(m.raw, [...iso], join(work, `${key}-raw`), ['--rate', '8']);
      expect(s.stderr).toMatch(codec);
      expect(s.record.store.source.dtype).toBe(m.dtype);
      expect(triangles(s.record)).toEqual(triangles(c.record));
      expect(Math.min(...triangles(s.record))).toBeGreaterThan(1000);
      for (const v of iso) {
        const tag = `-iso${Math.fround(v)}.ply`;
        expect(samePly(join(work, `${key}-store${tag}`), join(work, `${key}-raw${tag}`))).toBe('same');
      }
    }, 300_000);
  }

  it('neghip at the rate chosen from the data: within 1% of vtkMarchingCubes (triangles and area), each store alike', () => {
    const ref = JSON.parse(readFileSync(join(sharedData, 'reference/mc.json'), 'utf8')) as {
      volumes: {
        file: string;
        isosurfaces: { iso_nominal: number; iso: number; vtkMarchingCubes: { triangles: number; area: number } }[];
      }[];
    };
    const entry = ref.volumes.find((v) => v.file.includes('neghip'))!.isosurfaces.find((e) => e.iso_nominal === 80.37)!;
    for (const key of ['neghip_v04', 'neghip_v05', 'neghip_ozx']) {
      const s = extract(manifest[key].store, [entry.iso], join(work, `${key}-default`), ['--level', '0']);
      const got = s.record.isosurfaces[0];
      expect(Math.abs(got.triangles / entry.vtkMarchingCubes.triangles - 1), key).toBeLessThan(0.01);
      expect(Math.abs(got.surfaceArea / entry.vtkMarchingCubes.area - 1), key).toBeLessThan(0.01);
    }
  }, 300_000);

  it("a pyramid whose level 1 halves only z: every level drawn where its scale and translation put it; level 1 = zarr-python's array in core; bricks that nest, so the cut refines to level 0 and draws level 1 in level-0 voxels", async () => {
    const m = manifest.hydrogen_aniso;
    expect(m.shapes).toEqual([
      [128, 128, 128],
      [64, 128, 128],
      [64, 64, 64],
    ]);
    const store = await openStore(storeForLocation(m.store), m.store, { rate: 8 });
    expect(store.levels.map((l) => [l.path, ...l.layout.dims])).toEqual([
      ['scale0/hydrogen', 128, 128, 128],
      ['scale1/hydrogen', 128, 128, 64],
      ['scale2/hydrogen', 64, 64, 64],
    ]);
    // level 1 spans 2 level-0 voxels on z only; the Gaussian pyramid's translation puts it half a voxel up z
    expect(store.levelScales).toEqual([
      [1, 1, 1],
      [1, 1, 2],
      [2, 2, 2],
    ]);
    expect(store.levelOffsets).toEqual([
      [0, 0, 0],
      [0, 0, 0.5],
      [0.5, 0.5, 0.5],
    ]);
    expect(store.notes.join('\n')).not.toMatch(/not shown/);
    // bricks that nest: level 1's chunks (64 x 96 x 96) and level 2's (64^3) read as level 0's 96^3 bricks
    expect(store.levels.map((l) => l.layout.chunkEdge)).toEqual([96, 96, 96]);
    store.close?.();
    // level 1 as zarr-python reads it, compressed in core at rate 8: the same triangles
    const raw1 = join(work, 'hydrogen-level1_128x128x64_int16.raw');
    converterPython(
      "import sys, zarr, numpy as np\nnp.ascontiguousarray(zarr.open_group(sys.argv[1], mode='r')['scale1/hydrogen'][...]).astype('<i2').tofile(sys.argv[2])",
      [m.store, raw1],
    );
    const level1 = extract(m.store, [1500.5], join(work, 'aniso-level1'), ['--level', '1', '--rate', '8']);
    const core1 = extract(raw1, [1500.5], join(work, 'aniso-core1'), ['--rate', '8']);
    expect(triangles(level1.record)).toEqual(triangles(core1.record));
    expect(samePly(join(work, 'aniso-level1-iso1500.5.ply'), join(work, 'aniso-core1-iso1500.5.ply'))).toBe('same');
    // the view's cut: level 1's chunks (64 x 96 x 96, no cubes) are read as 96^3 bricks that nest in level 0's, so
    // the cut refines to full resolution: at the Fit, level 0 everywhere, the in-core surface of the raw exactly
    const fine = extract(m.raw, [1500.5], join(work, 'aniso-core0'), ['--rate', '8']);
    const ref = fine.record.isosurfaces[0];
    const full = extract(m.store, [1500.5], join(work, 'aniso-cut'), ['--view-box', '0,0,0,127,127,127', '--rate', '8']);
    expect(new Set(full.record.isosurfaces[0].cut.map((c: { level: number }) => c.level))).toEqual(new Set([0]));
    expect(triangles(full.record)).toEqual(triangles(fine.record));
    // within a budget that level 0 does not fit, level 1 is drawn, placed in level-0 voxels by its scale (1, 1, 2)
    // and translation: where level 0's surface is, within a voxel
    const coarse = extract(m.store, [1500.5], join(work, 'aniso-cut24'), [
      '--view-box',
      '0,0,0,127,127,127',
      '--rate',
      '8',
      '--cache-budget',
      '24',
    ]);
    const drawn = coarse.record.isosurfaces[0];
    expect(drawn.cut.some((c: { level: number }) => c.level === 1)).toBe(true);
    expect(coarse.record.store.gpuPeakBytes).toBeLessThanOrEqual(24 * 2 ** 20);
    for (const end of ['min', 'max'] as const)
      for (let a = 0; a < 3; a++) expect(Math.abs(drawn.bbox[end][a] - ref.bbox[end][a]), `${end}[${a}]`).toBeLessThan(1);
    expect(Math.abs(drawn.surfaceArea / ref.surfaceArea - 1)).toBeLessThan(0.03);
    // the converter's sidecar takes the same levels, so it fits
    const ranges = join(work, 'hydrogen-ranges.zarr');
    execFileSync(process.execPath, [join(repoRoot, 'scripts/convert.mjs'), m.store, '--out', ranges, '--ranges-only', '--quiet'], {
      timeout: 300_000,
      stdio: 'pipe',
    });
    const r = cli('extract', m.store, '--level', '1', '--rate', '8', '--iso', '1500.5', '--ranges', ranges);
    expect(r.status, r.stderr).toBe(0);
    expect(r.stderr).toMatch(/per-brick ranges from .*hydrogen-ranges.zarr \(rate 8\)/);
  }, 300_000);

  it("the .ozx over HTTP (range requests into the zip): every brick of every level = the folder store's", async () => {
    // in this process (the CLI would block the event loop that serves it)
    await expectSameBricks(`${base}/stores/neghip.ozx`, manifest.neghip_v05.store);
  }, 300_000);

  it('zip files that break the rules are refused by name; a deflated zip and a zipped folder open', async () => {
    const dir = join(work, 'zips');
    mkdirSync(dir, { recursive: true });
    const src = readFileSync(manifest.neghip_ozx.store);
    // not a zip; cut short (its end record lost); a central directory that points past the file
    writeFileSync(join(dir, 'text.ozx'), 'not a zip at all');
    writeFileSync(join(dir, 'short.ozx'), src.subarray(0, src.length - 200));
    const bent = Buffer.from(src);
    const eocd = bent.lastIndexOf(Buffer.from([0x50, 0x4b, 0x05, 0x06]));
    bent.writeUInt32LE(bent.length + 1000, eocd + 16);
    writeFileSync(join(dir, 'bent.ozx'), bent);
    // re-zipped by Python's zipfile: deflated, bzip2 (a method we do not read), and inside a folder
    converterPython(
      `
import sys, zipfile
src, out = sys.argv[1], sys.argv[2]
with zipfile.ZipFile(src) as z:
    names = [(n, z.read(n)) for n in z.namelist()]
for name, method, prefix in [('deflated.zip', zipfile.ZIP_DEFLATED, ''), ('bzip2.zip', zipfile.ZIP_BZIP2, ''), ('folder.zip', zipfile.ZIP_STORED, 'neghip.ome.zarr/')]:
    with zipfile.ZipFile(out + '/' + name, 'w', method) as z:
        for n, b in names:
            z.writestr(prefix + n, b)
`,
      [manifest.neghip_ozx.store, dir],
    );
    const refused: [string, RegExp][] = [
      ['text.ozx', /text.ozx: not a zip file \(no end of central directory record/],
      ['short.ozx', /short.ozx: not a zip file|short.ozx: not a readable zip/],
      ['bent.ozx', /bent.ozx: not a readable zip \(its central directory (lies past its end|is cut short)\)/],
      ['bzip2.zip', /bzip2.zip: entry .* is compressed with zip method 12/],
    ];
    for (const [name, message] of refused) {
      const r = cli('info', join(dir, name));
      expect(r.status, name).toBe(1);
      expect(r.stderr, name).toMatch(message);
    }
    for (const name of ['deflated.zip', 'folder.zip']) await expectSameBricks(join(dir, name), manifest.neghip_v05.store);
  }, 300_000);
});
