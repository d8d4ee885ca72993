// Issue 47, "Series in": numbered volume files as a read-only Zarr store
// (src/volume/series-files.ts checks and reads them, src/store/zarr/
// file-series-store.ts is the store). Files written by NumPy (raw, NRRD big
// endian and gzip) and tifffile (3-D stacks); truth is NumPy's array of each
// file (tifffile's read for TIFF). Read through zarrita (every time point, z
// slabs with a padded last one) and through our openStore (a store of
// lossless chunks with a t axis: a brick's values at any time point). Files
// are read only when a chunk of them is asked for; mismatched sets are
// refused naming the file.
import { mkdtempSync, readdirSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import * as zarr from 'zarrita';
import { afterAll, beforeAll, describe, expect, it } from 'vitest';
import { openStore } from '../../../src/store/zarr/open-store.ts';
import { FileSeriesStore, slabPlanes } from '../../../src/store/zarr/file-series-store.ts';
import { nrrdSeries, rawSeries, SeriesError, tiffPageCount, tiffSeries } from '../../../src/volume/series-files.ts';
import { runPython } from '../../helpers/python.ts';

const work = mkdtempSync(join(tmpdir(), 'file-series-'));
afterAll(() => rmSync(work, { recursive: true, force: true }));

// x, y, z of every volume here
const X = 20;
const Y = 24;
const Z = 70;
const T = 3;

beforeAll(() => {
  runPython(
    `
import sys, os, gzip, numpy as np, tifffile
d = sys.argv[1]; X, Y, Z, T = (int(a) for a in sys.argv[2:6])
rng = np.random.default_rng(47)
os.makedirs(f'{d}/raw'); os.makedirs(f'{d}/tif'); os.makedirs(f'{d}/nrrd'); os.makedirs(f'{d}/truth')
for t in range(T):
    v = rng.integers(0, 65535, size=(Z, Y, X), dtype=np.uint16)          # [z][y][x], x fastest
    v.tofile(f'{d}/raw/vol_{t}_{X}x{Y}x{Z}_uint16.raw')
    v.tofile(f'{d}/truth/raw_{t}.bin')
    s = rng.integers(-100, 100, size=(Z // 7, Y, X), dtype=np.int16)
    tifffile.imwrite(f'{d}/tif/t{t + 1}.tif', s)                           # a 3-D stack: one page per z
    tifffile.imread(f'{d}/tif/t{t + 1}.tif').astype('<i2').tofile(f'{d}/truth/tif_{t}.bin')
    f = rng.random(size=(Z, Y, X), dtype=np.float32)
    head = f'NRRD0004\\ntype: float\\ndimension: 3\\nsizes: {X} {Y} {Z}\\nendian: {"big" if t == 0 else "little"}\\nencoding: {"raw" if t == 0 else "gzip"}\\n\\n'
    data = f.astype('>f4' if t == 0 else '<f4').tobytes()
    open(f'{d}/nrrd/n{t}.nrrd', 'wb').write(head.encode() + (data if t == 0 else gzip.compress(data)))
    f.astype('<f4').tofile(f'{d}/truth/nrrd_{t}.bin')
# mismatched sets
v = np.zeros((Z, Y, X), np.uint16)
os.makedirs(f'{d}/bad')
v.tofile(f'{d}/bad/vol_0_{X}x{Y}x{Z}_uint16.raw')
v[:-1].tofile(f'{d}/bad/vol_1_{X}x{Y}x{Z}_uint16.raw')
tifffile.imwrite(f'{d}/bad/t1.tif', np.zeros((10, Y, X), np.int16))
tifffile.imwrite(f'{d}/bad/t2.tif', np.zeros((9, Y, X), np.int16))
`,
    [work, String(X), String(Y), String(Z), String(T)],
  );
}, 120_000);

const fileOf = (path: string) => new File([readFileSync(path)], path.split('/').pop()!);
const filesIn = (dir: string, pattern: RegExp) =>
  readdirSync(join(work, dir))
    .filter((n) => pattern.test(n))
    .sort()
    .map((n) => fileOf(join(work, dir, n)));
const truth = (kind: string, t: number) => new Uint8Array(readFileSync(join(work, 'truth', `${kind}_${t}.bin`)));

/** Every time point read by zarrita from the store equals the truth. */
async function readsAll(store: FileSeriesStore, kind: string, dtype: string): Promise<void> {
  const arr = await zarr.open.v2(zarr.root(store).resolve('0'), { kind: 'array', attrs: false });
  expect(arr.dtype).toBe(dtype);
  expect(arr.shape).toEqual([T, store.series.dims[2], Y, X]);
  for (let t = 0; t < T; t++) {
    const got = (await zarr.get(arr, [t, null, null, null])).data as ArrayBufferView;
    const bytes = new Uint8Array(got.buffer, got.byteOffset, got.byteLength);
    expect(Buffer.compare(Buffer.from(bytes), Buffer.from(truth(kind, t))), `${kind} time point ${t}`).toBe(0);
  }
}

describe('a series of volume files as a Zarr store', () => {
  it('slabs: a multiple of 64 planes, else a power of two, the whole volume when it fits', () => {
    expect(slabPlanes([48, 48, 48], 1)).toBe(48);
    expect(slabPlanes([256, 256, 1000], 1)).toBe(256);
    expect(slabPlanes([512, 512, 1000], 2)).toBe(32);
    expect(slabPlanes([8192, 8192, 10], 4)).toBe(1);
  });

  it('raw: zarrita reads every time point as NumPy wrote it; nothing is read before a chunk is asked for', async () => {
    const files = filesIn('raw', /\.raw$/);
    const series = rawSeries(files, [X, Y, Z], 'uint16');
    // 16 planes per chunk: 5 slabs along z, the last padded
    const store = new FileSeriesStore(series, 'vol_0 … vol_2', X * Y * 2 * 16);
    expect(store.planes).toBe(16);
    expect(store.chunksRead).toBe(0);
    const last = await store.get('/0/1.4.0.0');
    expect(last!.byteLength).toBe(16 * X * Y * 2);
    expect(Buffer.compare(Buffer.from(last!.subarray(0, 6 * X * Y * 2)), Buffer.from(truth('raw', 1).subarray(64 * X * Y * 2)))).toBe(0);
    expect(last!.subarray(6 * X * Y * 2).every((b) => b === 0)).toBe(true);
    expect(await store.get('/0/3.0.0.0')).toBeUndefined();
    expect(await store.get('/0/0.5.0.0')).toBeUndefined();
    await readsAll(store, 'raw', 'uint16');
  });

  it('raw: our openStore sees a store of lossless chunks with a t axis; a brick at a time point holds its values', async () => {
    const series = rawSeries(filesIn('raw', /\.raw$/), [X, Y, Z], 'uint16');
    const store = new FileSeriesStore(series, 'raw series', X * Y * 2 * 16);
    for (const t of [0, 2]) {
      const s = await openStore(store, 'raw series', { rate: 8, time: t });
      try {
        expect(s.time).toMatchObject({ index: t, count: T });
        expect(s.levels).toHaveLength(1);
        expect(s.levels[0].layout.dims).toEqual([X, Y, Z]);
        const B = s.levels[0].layout.chunkEdge;
        expect(B).toBe(64);
        // brick (0, 0, 1): z 64..69 of the volume
        const brick = new Float32Array((await s.readChunk(0, 0 + 1 * 1 * 1)).buffer.slice(0));
        const want = new Uint16Array(truth('raw', t).buffer.slice(0));
        for (const [x, y, z] of [
          [0, 0, 64],
          [19, 23, 69],
          [7, 11, 66],
        ])
          expect(brick[x + B * (y + B * (z - 64))]).toBe(want[x + X * (y + Y * z)]);
      } finally {
        s.close?.();
      }
    }
  });

  it('NRRD: big-endian raw and gzip files, each read as NumPy wrote it', async () => {
    const series = await nrrdSeries(filesIn('nrrd', /\.nrrd$/));
    expect(series.dims).toEqual([X, Y, Z]);
    await readsAll(new FileSeriesStore(series, 'nrrd', X * Y * 4 * 32), 'nrrd', 'float32');
  });

  it('TIFF: 3-D stacks (one per time point) read as tifffile reads them', async () => {
    const files = filesIn('tif', /\.tif$/);
    expect(await tiffPageCount(files[0])).toBe(10);
    const series = await tiffSeries(files);
    expect(series.dims).toEqual([X, Y, 10]);
    const store = new FileSeriesStore(series, 'tif', X * Y * 2 * 4);
    await readsAll(store, 'tif', 'int16');
  });

  it('mismatched sets are refused naming the file', async () => {
    expect(() => rawSeries(filesIn('bad', /\.raw$/), [X, Y, Z], 'uint16')).toThrow(
      new SeriesError(`vol_1_${X}x${Y}x${Z}_uint16.raw: 66,240 bytes; the series' shape 20×24×70 uint16 needs 67,200`),
    );
    // a name that says another shape than the series'
    const other = new File([new Uint8Array(X * Y * Z)], `vol_1_${X}x${Y}x${Z}_uint8.raw`);
    expect(() => rawSeries([filesIn('raw', /\.raw$/)[0], other], [X, Y, Z], 'uint16')).toThrow(
      /vol_1_20x24x70_uint8\.raw: the name says 20×24×70 uint8/,
    );
    await expect(tiffSeries(filesIn('bad', /\.tif$/))).rejects.toThrow("t2.tif: 20×24×9, the series' first file t1.tif is 20×24×10");
    const shortNrrd = new File(
      [new TextEncoder().encode('NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4 4 4\nencoding: raw\n\n'), new Uint8Array(10)],
      'b.nrrd',
    );
    const nrrds = filesIn('nrrd', /\.nrrd$/);
    await expect(nrrdSeries([nrrds[0], shortNrrd])).rejects.toThrow(
      "b.nrrd: 4×4×4 uint8, the series' first file n0.nrrd is 20×24×70 float32",
    );
    const truncated = new File(
      [new TextEncoder().encode(`NRRD0004\ntype: float\ndimension: 3\nsizes: ${X} ${Y} ${Z}\nencoding: raw\n\n`), new Uint8Array(10)],
      'c.nrrd',
    );
    await expect(nrrdSeries([nrrds[0], truncated])).rejects.toThrow('c.nrrd: truncated');
  });
});
