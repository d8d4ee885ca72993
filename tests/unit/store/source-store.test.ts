// Stores of lossless chunks, shaped like the public collections (issue 28),
// written by zarr-python (tests/fixtures/source-stores.py): Zarr v3 + zstd +
// sharding uint8 (Open SciVis), Zarr v2 + blosc uint16 5-D with chunks one
// plane thick (IDR), Zarr v2 + zstd uint8 64x128x128 chunks (OpenOrganelle),
// gzip int16 201x131x67 in 100^3 chunks (and the same array in 64^3), lz4
// float64; each a 3-level OME-Zarr pyramid. For each, `extract STORE --level
// 0 --rate 8` gives the surfaces of `extract name_XxYxZ_dtype.raw --rate 8`
// (the same array as a raw file, in core) triangle for triangle, compared
// as sets of vertex positions by NumPy over the two PLY files; the source
// value range is NumPy's; the voxel size is the store's scale. Broken
// stores are refused by name.
import { execFileSync } from 'node:child_process';
import { mkdtempSync, rmSync } from 'node:fs';
import { readFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, it } from 'vitest';
import { repoRoot } from '../../helpers/python.ts';
import { cli, samePly } from './stores.ts';

const work = mkdtempSync(join(tmpdir(), 'source-stores-'));
interface Entry {
  store: string;
  raw: string;
  iso: number[];
  range: [number, number];
  dtype: string;
  voxelSize: [number, number, number];
  rawT1C1?: string;
  isoT1C1?: number[];
}
let manifest: Record<string, Entry> & { errors: Record<string, string> };

function extract(input: string, iso: number[], prefix: string, extra: string[] = []) {
  const json = `${prefix}.json`;
  const r = cli('extract', input, `--iso=${iso.join(',')}`, '--rate', '8', '--ply', prefix, '--json', json, ...extra);
  expect(r.status, r.stderr).toBe(0);
  return { record: JSON.parse(readFileSync(json, 'utf8')), stderr: r.stderr };
}

beforeAll(() => {
  const out = execFileSync(join(repoRoot, '.venv-converter/bin/python'), [join(repoRoot, 'tests/fixtures/source-stores.py'), work], {
    encoding: 'utf8',
    timeout: 600_000,
    stdio: ['ignore', 'pipe', 'ignore'],
  });
  manifest = JSON.parse(out);
}, 600_000);
afterAll(() => rmSync(work, { recursive: true, force: true }));

describe('stores of lossless chunks = the same array in core', () => {
  for (const [name, codec, bricks] of [
    ['scivis', /Zarr v3 store of uint8 \(sharding_indexed\(bytes, zstd\)\)/, 32],
    ['idr', /Zarr v2 store of uint16 \(blosc\)/, 64],
    ['organelle', /Zarr v2 store of uint8 \(zstd\)/, 64],
    ['gzip', /Zarr v3 store of int16 \(bytes \+ gzip\)/, 100],
    ['gzip64', /Zarr v3 store of int16 \(bytes \+ gzip\)/, 64],
    ['f64', /Zarr v3 store of float64 \(bytes \+ numcodecs.lz4\)/, 32],
  ] as const) {
    it(`${name}: level 0 at two isovalues, vertex for vertex; value range and voxel size`, () => {
      const m = manifest[name];
      const s = extract(m.store, m.iso, join(work, `${name}-store`), ['--level', '0']);
      const c = extract(m.raw, m.iso, join(work, `${name}-raw`));
      expect(s.stderr).toMatch(codec);
      expect(s.record.store.chunkEdge).toBe(bricks);
      expect(s.record.store.levels).toBe(3);
      const tri = (r: { isosurfaces: { triangles: number }[] }) => r.isosurfaces.map((x) => x.triangles);
      expect(tri(s.record)).toEqual(tri(c.record));
      expect(Math.min(...tri(s.record))).toBeGreaterThan(5000);
      for (const iso of m.iso) {
        const tag = `-iso${Math.fround(iso)}.ply`;
        expect(samePly(join(work, `${name}-store${tag}`), join(work, `${name}-raw${tag}`))).toBe('same');
      }
      // the level was read whole (no range arrays): its source range is NumPy's over the array
      expect(s.record.store.sourceValueRange).toEqual(m.range.map((v) => Math.fround(v)));
      expect(s.record.store.voxelSize).toEqual(m.voxelSize);
      expect(s.record.store.unit).toBe('micrometer');
      expect(s.record.store.source.dtype).toBe(m.dtype);
      expect(s.record.store.chunks).toBe(s.record.store.levelChunks);
    }, 300_000);
  }

  it('a 5-D store: time point 1, channel 1 by --time / --channel = that slice in core', () => {
    const m = manifest.idr;
    const s = extract(m.store, m.isoT1C1!, join(work, 'idr-t1c1-store'), ['--level', '0', '--time', '1', '--channel', '1']);
    const c = extract(m.rawT1C1!, m.isoT1C1!, join(work, 'idr-t1c1-raw'));
    expect(s.record.store.source.time).toEqual({ index: 1, count: 2 });
    expect(s.record.store.source.channel).toEqual({ index: 1, count: 2 });
    expect(s.record.isosurfaces.map((x: { triangles: number }) => x.triangles)).toEqual(
      c.record.isosurfaces.map((x: { triangles: number }) => x.triangles),
    );
    const tag = `-iso${Math.fround(m.isoT1C1![0])}.ply`;
    expect(samePly(join(work, `idr-t1c1-store${tag}`), join(work, `idr-t1c1-raw${tag}`))).toBe('same');
    const bad = cli('extract', m.store, '--iso', '300', '--time', '2');
    expect(bad.status).toBe(1);
    expect(bad.stderr).toMatch(/idr.zarr level 0: time point 2 is outside 0..1/);
  }, 300_000);

  it('a ranges sidecar (convert --ranges-only): only the bricks the surface needs are fetched, the same surface', () => {
    const m = manifest.gzip64;
    const ranges = join(work, 'gzip64-ranges.zarr');
    execFileSync(process.execPath, [join(repoRoot, 'scripts/convert.mjs'), m.store, '--out', ranges, '--ranges-only', '--quiet'], {
      timeout: 600_000,
      stdio: 'pipe',
    });
    const iso = [2300.37];
    const s = extract(m.store, iso, join(work, 'gzip64-ranged'), ['--level', '0', '--ranges', ranges]);
    const c = extract(m.raw, iso, join(work, 'gzip64-ranged-raw'));
    expect(s.stderr).toMatch(/per-brick ranges from .*gzip64-ranges.zarr \(rate 8\)/);
    expect(s.record.isosurfaces[0].triangles).toBe(c.record.isosurfaces[0].triangles);
    expect(s.record.isosurfaces[0].triangles).toBeGreaterThan(100);
    const tag = `-iso${Math.fround(iso[0])}.ply`;
    expect(samePly(join(work, `gzip64-ranged${tag}`), join(work, `gzip64-ranged-raw${tag}`))).toBe('same');
    expect(s.record.store.chunks).toBeGreaterThan(0);
    expect(s.record.store.chunks).toBeLessThan(s.record.store.levelChunks);
    // ranges for another rate are not used (said), a sidecar of another store is refused by name
    const other = cli('extract', m.store, '--level', '0', '--ranges', ranges, '--rate', '4', '--iso=2300.37');
    expect(other.status, other.stderr).toBe(0);
    expect(other.stderr).toMatch(
      /gzip64-ranges.zarr is not used: its ranges are of the values at rate 8, the bricks are compressed at rate 4/,
    );
    const wrong = cli('extract', manifest.scivis.store, '--level', '0', '--ranges', ranges, '--iso', '100');
    expect(wrong.status).toBe(1);
    expect(wrong.stderr).toMatch(/gzip64-ranges.zarr: its ranges are not of this store's bricks/);
  }, 300_000);

  it("NaN (voxels, and the fill value of chunks left out) becomes the brick's smallest finite value; counted, never encoded", () => {
    const m = manifest.nan;
    const json = join(work, 'nan.json');
    const r = cli('extract', m.store, '--level', '0', '--rate', '8', '--iso', '5', '--json', json);
    expect(r.status, r.stderr).toBe(0);
    const rec = JSON.parse(readFileSync(json, 'utf8'));
    expect(rec.store.sourceDecode.nonFinite).toBeGreaterThan(0);
    expect(rec.store.sourceValueRange).toEqual(m.range.map((v) => Math.fround(v)));
    expect(rec.isosurfaces[0].triangles).toBeGreaterThan(1000);
    expect(rec.valueRange.every(Number.isFinite)).toBe(true);
  }, 300_000);

  it('info STORE: levels, codecs, type, axes, bricks, voxel size; a folder that is no store is named', () => {
    const json = join(work, 'info.json');
    const r = cli('info', manifest.idr.store, '--rate', '8', '--json', json);
    expect(r.status, r.stderr).toBe(0);
    const rec = JSON.parse(readFileSync(json, 'utf8'));
    expect(rec.kind).toBe('zarr-store');
    expect(rec.source).toMatchObject({ format: 'Zarr v2', codecs: ['blosc'], dtype: 'uint16', axes: ['t', 'c', 'z', 'y', 'x'], rate: 8 });
    expect(rec.levels.map((l: { dims: number[] }) => l.dims)).toEqual([
      [90, 70, 40],
      [45, 35, 20],
      [22, 17, 10],
    ]);
    expect(rec.voxelSize).toEqual(manifest.idr.voxelSize);
    const folder = cli('info', work);
    expect(folder.status).toBe(1);
    expect(folder.stderr).toMatch(/a folder, but not a Zarr store \(no zarr.json, .zgroup or .zarray at its root\)/);
  }, 300_000);

  it('refuses an unknown codec, complex values, a 2-D image and a corrupt chunk, naming them', () => {
    const e = manifest.errors;
    const bz2 = cli('extract', e.bz2, '--iso', '3');
    expect(bz2.status).toBe(1);
    expect(bz2.stderr).toMatch(
      /bz2.zarr level 0: its chunks use the codec "bz2", which this reader does not have \(it reads blosc, lz4, zstd, gzip/,
    );
    const cplx = cli('extract', e.complex, '--iso', '3');
    expect(cplx.status).toBe(1);
    expect(cplx.stderr).toMatch(/complex.zarr level 0: its values are complex numbers \(complex64\)/);
    const flat = cli('extract', e.image2d, '--iso', '3');
    expect(flat.status).toBe(1);
    expect(flat.stderr).toMatch(/image2d.zarr level 0: a 2-D image \(shape \[64, 64\]\); isosurfaces need a 3-D volume/);
    const corrupt = cli('extract', e.corrupt, '--iso', '100');
    expect(corrupt.status).toBe(1);
    expect(corrupt.stderr).toMatch(/corrupt.zarr level 0 chunk \[1, 0, 1\]: does not decode \(.*zstd/);
    expect(corrupt.stderr).not.toMatch(/usage/i);
  }, 300_000);
});
