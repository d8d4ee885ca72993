// TIFF through libtiff (+ zlib, libjpeg-turbo) compiled to Wasm, against
// tifffile/imagecodecs: the shared files' expected.json, and variants written
// by tifffile in the test (every sample type, deflate/LZW/PackBits/JPEG,
// predictors, tiles, planar, big-endian, BigTIFF, stacks of files).
import { createHash } from 'node:crypto';
import { readdirSync } from 'node:fs';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, test } from 'vitest';
import {
  loadTiffStack,
  loadTiffWasm,
  sampleStats,
  TiffError,
  TiffReader,
  type SampleArray,
  type TiffSource,
} from '../../../src/loaders/tiff.ts';
import { makeFixtures, readBytes, sharedData, sharedExpected, type Fixtures } from './fixtures.ts';

const expected = sharedExpected('tiff');

function sha256(data: SampleArray): string {
  return createHash('sha256')
    .update(new Uint8Array(data.buffer, data.byteOffset, data.byteLength))
    .digest('hex');
}

const source = (dir: string, name: string): TiffSource => ({ name, bytes: readBytes(join(dir, name)) });

describe('shared TIFF files match tifffile (expected.json)', () => {
  test.each(Object.keys(expected))('%s', async (name) => {
    const e = expected[name];
    const reader = await TiffReader.open(readBytes(join(sharedData, 'tiff', name)), name);
    const page = reader.pages[0];
    expect(reader.pageCount).toBe(e.pages);
    expect(page.width).toBe(e.width);
    expect(page.height).toBe(e.height);
    expect(page.bitsPerSample).toBe(e.bits_per_sample);
    expect(page.samplesPerPixel).toBe(e.samples_per_pixel);
    expect([page.sampleFormat, page.sampleFormatName]).toEqual([e.sample_format.code, e.sample_format.name]);
    expect([page.compression, page.compressionName]).toEqual([e.compression.code, e.compression.name]);
    expect([page.photometric, page.photometricName]).toEqual([e.photometric.code, e.photometric.name]);
    expect(page.planarConfig).toBe(e.planar_config.code);
    expect(page.tiled).toBe(e.tiled);
    expect(page.bigTiff).toBe(e.bigtiff);
    expect(page.bigEndian).toBe(e.byteorder === '>');
    reader.close();

    const v = await loadTiffStack({ name, bytes: readBytes(join(sharedData, 'tiff', name)) });
    expect(v.pages.length).toBe(e.decoded.pages_in_series);
    expect(v.dtype).toBe({ '|u1': 'uint8', '<u2': 'uint16' }[e.decoded.dtype as string]);
    expect(v.data.length).toBe(e.decoded.shape.reduce((a: number, b: number) => a * b, 1));
    expect(sha256(v.data)).toBe(e.decoded.sha256_pyxs);
    const s = sampleStats(v.data);
    expect(s.min).toBe(e.decoded.min);
    expect(s.max).toBe(e.decoded.max);
    expect(s.mean).toBeCloseTo(e.decoded.mean, 9);
    expect(v.imagej !== undefined).toBe(e.imagej);
  });

  test('Files (Blobs) stream into the heap one at a time and decode the same', async () => {
    const name = 'morpholibj_bat-cochlea-volume.tif';
    const bytes = readBytes(join(sharedData, 'tiff', name));
    const v = await loadTiffStack({ name, bytes: new Blob([bytes]) });
    expect(sha256(v.data)).toBe(expected[name].decoded.sha256_pyxs);
  });

  test('ImageJ stacks carry their voxel spacing', async () => {
    const v = await loadTiffStack(source(join(sharedData, 'tiff'), 'imagejs_stack.tif'));
    expect(v.dims).toEqual([128, 128, 10]);
    expect(v.imagej?.images).toBe(10);
    expect(v.spacing?.[0]).toBeCloseTo(0.064, 6);
    expect(v.unit).toBe('micron');
  });
});

describe('TIFF variants written by tifffile', () => {
  let fx: Fixtures;
  beforeAll(() => {
    fx = makeFixtures();
  });
  afterAll(() => fx?.dispose());

  test('every sample type, codec, predictor, tiling and layout decodes like tifffile', async () => {
    const names = Object.keys(fx.expected.tiff).filter((n) => n.endsWith('.tif'));
    expect(names.length).toBeGreaterThanOrEqual(15);
    for (const name of names) {
      const e = fx.expected.tiff[name];
      const v = await loadTiffStack(source(fx.dir, name));
      expect(v.dtype, name).toBe(e.dtype);
      expect(v.dims, name).toEqual([e.width, e.height, e.pages]);
      expect(v.samplesPerPixel, name).toBe(e.samples_per_pixel);
      const p = v.pages[0];
      expect([p.compression, p.planarConfig, p.tiled, p.bitsPerSample], name).toEqual([
        e.compression,
        e.planar_config,
        e.tiled,
        e.bits_per_sample,
      ]);
      const s = sampleStats(v.data);
      if (e.lossy) {
        // JPEG: libjpeg-turbo versions may round the inverse DCT / colour
        // conversion differently; compare sample by sample within a few levels.
        const reference = readBytes(join(fx.dir, `${name}.decoded.raw`));
        expect(reference.length, name).toBe(v.data.length);
        let worst = 0;
        let differ = 0;
        for (let i = 0; i < reference.length; i++) {
          const d = Math.abs(reference[i] - v.data[i]);
          worst = Math.max(worst, d);
          if (d > 0) differ++;
        }
        expect(worst, name).toBeLessThanOrEqual(2);
        expect(differ / reference.length, name).toBeLessThan(0.05);
        expect(Math.abs(s.mean - e.mean), name).toBeLessThan(0.05);
      } else {
        expect(sha256(v.data), name).toBe(e.sha256_pyxs);
        expect([s.min, s.max], name).toEqual([e.min, e.max]);
        expect(s.mean, name).toBeCloseTo(e.mean, 6);
      }
    }
  });

  test('ImageJ spacing and unit from a hyperstack written by tifffile', async () => {
    const e = fx.expected.tiff['imagej_spacing.tif'];
    const v = await loadTiffStack(source(fx.dir, 'imagej_spacing.tif'));
    expect(v.spacing![0]).toBeCloseTo(e.spacing[0], 6);
    expect(v.spacing![1]).toBeCloseTo(e.spacing[1], 6);
    expect(v.spacing![2]).toBeCloseTo(e.spacing[2], 6);
    expect(v.unit).toBe(e.unit);
  });

  test('a stack of single-page files is ordered by name, numbers as numbers', async () => {
    const e = fx.expected.tiff['stack/'];
    const dir = join(fx.dir, 'stack');
    // Shuffled, and as text "slice10" < "slice2": the loader must still give 1, 2, ..., 12.
    const files = readdirSync(dir)
      .sort()
      .reverse()
      .map((n) => source(dir, n));
    const progress: number[] = [];
    const v = await loadTiffStack(files, { onProgress: (done) => progress.push(done), yieldBetweenPages: true });
    expect(v.files).toEqual(e.files);
    expect(v.dims).toEqual([e.width, e.height, e.pages]);
    expect(v.dtype).toBe(e.dtype);
    expect(sha256(v.data)).toBe(e.sha256_pyxs);
    expect(progress).toEqual(Array.from({ length: 12 }, (_, i) => i + 1));
  });

  test('unsupported files are refused with a message naming the file and the reason', async () => {
    const reasons = fx.expected.tiff.unsupported as Record<string, string>;
    for (const [name, reason] of Object.entries(reasons)) {
      await expect(loadTiffStack(source(fx.dir, name)), name).rejects.toThrow(new RegExp(`^${name.replace('.', '\\.')}: .*${reason}`));
    }
  });

  test('a stack whose files differ in shape names the odd file', async () => {
    const dir = join(fx.dir, 'stack');
    const files = [source(dir, 'slice1.tif'), source(dir, 'slice2.tif'), source(fx.dir, 'u8_deflate.tif')];
    await expect(loadTiffStack(files)).rejects.toThrow(
      /^u8_deflate\.tif: its pages \(53×37 uint8\) do not match the stack \(22×18 uint16\)/,
    );
  });
});

describe('bad files', () => {
  const lzw = () => readBytes(join(sharedData, 'tiff', 'imagejs_image-lzw.tif'));
  const stack = () => readBytes(join(sharedData, 'tiff', 'imagejs_stack.tif'));

  test('not a TIFF, empty, truncated header, truncated data, corrupt LZW', async () => {
    await expect(loadTiffStack({ name: 'photo.tif', bytes: new TextEncoder().encode('GIF89a...') })).rejects.toThrow(
      /^photo\.tif: not a TIFF file/,
    );
    await expect(loadTiffStack({ name: 'empty.tif', bytes: new Uint8Array(0) })).rejects.toThrow(/^empty\.tif: not a TIFF file/);
    await expect(loadTiffStack({ name: 'hdr.tif', bytes: new Uint8Array([0x49, 0x49, 42, 0, 8, 0, 0, 0, 1, 0]) })).rejects.toThrow(
      /^hdr\.tif: truncated or corrupt TIFF/,
    );
    // The LZW file keeps its directory at the end: cutting it loses the directory.
    await expect(loadTiffStack({ name: 'cut-lzw.tif', bytes: lzw().slice(0, 500_000) })).rejects.toThrow(
      /^cut-lzw\.tif: truncated or corrupt TIFF/,
    );
    // The ImageJ stack keeps its directories first: cutting it loses pixel data.
    await expect(loadTiffStack({ name: 'cut-stack.tif', bytes: stack().slice(0, 200_000) })).rejects.toThrow(
      // Checked before anything is allocated: the page's strips lie past the end of the cut file.
      /^cut-stack\.tif: truncated or corrupt file: page \d+ is 128×128 uint16 \(32\.0 KiB\) but its strips hold 0 B/,
    );
    const corrupt = lzw();
    for (let i = 400_000; i < 400_064; i++) corrupt[i] = 0xff;
    await expect(loadTiffStack({ name: 'corrupt-lzw.tif', bytes: corrupt })).rejects.toThrow(/^corrupt-lzw\.tif: page 0: /);
  });

  test('Wasm memory is released after every file, good or bad', async () => {
    const m = await loadTiffWasm();
    const good = { name: 'good.tif', bytes: lzw() };
    const cut = { name: 'cut.tif', bytes: stack().slice(0, 200_000) };
    await loadTiffStack(good);
    await expect(loadTiffStack(cut)).rejects.toThrow(TiffError);
    const heap = m.HEAPU8.length;
    for (let i = 0; i < 12; i++) {
      await loadTiffStack(good);
      await expect(loadTiffStack(cut)).rejects.toThrow(TiffError);
      const r = await TiffReader.open(stack(), 's.tif');
      r.readPage(3);
      r.close();
    }
    // 12 leaked copies of the 1.1 MB file and its 24 MB decoded page would show.
    expect(m.HEAPU8.length).toBe(heap);
  });
});
