// Issue 13's classes of hostile LAS/LAZ and TIFF files, each reproduced: the
// reader refuses them with its own error naming the file, allocates nothing
// from the header's claims, and the next (valid) file still decodes to what
// laspy/tifffile read (../shared/data/*/expected.json). Failures inside the
// Wasm modules (traps) are simulated to check that the module is replaced and
// that close() never masks the outcome.
import { createHash } from 'node:crypto';
import { join } from 'node:path';
import { describe, expect, test } from 'vitest';
import { lasCommand } from '../../../src/cli/commands/las.ts';
import { LasError, LasReader, loadLasWasm, loadPointCloud } from '../../../src/loaders/las.ts';
import { loadTiffStack, loadTiffWasm, TiffError, TiffReader } from '../../../src/loaders/tiff.ts';
import { hugeTiffPage } from '../../fuzz/wasm-mutate.ts';
import { readBytes, sharedData, sharedExpected } from './fixtures.ts';

const lasExpected = sharedExpected('las');
const tiffExpected = sharedExpected('tiff');
const las = (name: string) => readBytes(join(sharedData, 'las', name));
const tif = (name: string) => readBytes(join(sharedData, 'tiff', name));

async function lasRejects(bytes: Uint8Array, name: string, readAll = true): Promise<LasError> {
  try {
    const r = await LasReader.open(bytes, name);
    try {
      while (readAll && r.read(1 << 18, { positions: true, xyz: true, records: true }));
    } finally {
      r.close();
    }
  } catch (e) {
    expect(e).toBeInstanceOf(LasError);
    expect((e as Error).message.startsWith(`${name}: `)).toBe(true);
    return e as LasError;
  }
  throw new Error(`${name} was accepted`);
}

/** A valid file after a rejected one decodes as laspy reads it. */
async function lasStillWorks(): Promise<void> {
  const e = lasExpected['laspy_simple.laz'];
  const pc = await loadPointCloud(las('laspy_simple.laz'), 'laspy_simple.laz');
  expect(pc.count).toBe(e.point_count);
  const r = await LasReader.open(las('laspy_simple.laz'), 'again.laz');
  const hash = createHash('sha256');
  for (let c; (c = r.read(400, { records: true })); ) hash.update(c.records!);
  r.close();
  expect(hash.digest('hex')).toBe(e.points_record_sha256);
}

async function tiffStillWorks(): Promise<void> {
  const e = tiffExpected['imagejs_stack.tif'];
  const v = await loadTiffStack({ name: 'imagejs_stack.tif', bytes: tif('imagejs_stack.tif') });
  expect(v.dims).toEqual([e.width, e.height, e.pages]);
  expect(
    createHash('sha256')
      .update(new Uint8Array(v.data.buffer, v.data.byteOffset, v.data.byteLength))
      .digest('hex'),
  ).toBe(e.decoded.sha256_tifffile_layout);
}

/** A minimal LAS 1.4 file, point format 6, `n` points of `recordLength` bytes (extra bytes patterned). */
function makeLas14(n: number, recordLength: number): Uint8Array {
  const bytes = new Uint8Array(375 + n * recordLength);
  const dv = new DataView(bytes.buffer);
  bytes.set([0x4c, 0x41, 0x53, 0x46]);
  bytes[24] = 1;
  bytes[25] = 4;
  dv.setUint16(94, 375, true);
  dv.setUint32(96, 375, true);
  bytes[104] = 6;
  dv.setUint16(105, recordLength, true);
  for (let a = 0; a < 3; a++) dv.setFloat64(131 + 8 * a, 0.01, true);
  // Bounds (max, min per axis) cover X = i, Y = 2i, Z = 3i (scaled by 0.01).
  for (let a = 0; a < 3; a++) {
    dv.setFloat64(179 + 16 * a, 0.01 * (a + 1) * Math.max(0, n - 1), true);
    dv.setFloat64(187 + 16 * a, 0, true);
  }
  dv.setBigUint64(247, BigInt(n), true);
  for (let i = 0; i < n; i++) {
    const p = 375 + i * recordLength;
    for (let a = 0; a < 3; a++) dv.setInt32(p + 4 * a, (a + 1) * i, true);
    bytes[p + 14] = 0x11; // return 1 of 1
    for (let j = 30; j < recordLength; j++) bytes[p + j] = (i * 7 + j) & 0xff;
  }
  return bytes;
}

describe('LAS/LAZ', () => {
  test('LAS 1.4: point count × record length that wraps 64 bits is refused before LASzip reads', async () => {
    const bytes = makeLas14(3, 16388);
    new DataView(bytes.buffer).setBigUint64(247, (1n << 64n) / 16388n + 1n, true);
    const e = await lasRejects(bytes, 'wrap14.las');
    expect(e.message).toMatch(/^wrap14\.las: truncated file: the header announces 1125[0-9]{12} points of 16388 bytes/);
    await lasStillWorks();
  });

  test('long records come in chunks that fit a 32-bit _malloc, byte for byte as in the file', async () => {
    const n = 5000;
    const bytes = makeLas14(n, 16388);
    const r = await LasReader.open(bytes, 'long-records.las');
    expect(r.header.pointCount).toBe(n);
    const m = await loadLasWasm();
    let at = 0;
    for (let c; (c = r.read(1 << 18, { records: true, positions: true })); at += c.count) {
      // 2^18 × 16388 bytes would wrap past 4 GiB in wasm32: the chunk is shortened instead.
      expect(c.count * 16388).toBeLessThanOrEqual(64 << 20);
      const want = bytes.subarray(375 + at * 16388, 375 + (at + c.count) * 16388);
      // Buffer.equals: a deep toEqual over 64 MiB would take minutes.
      expect(
        Buffer.from(c.records!.buffer, c.records!.byteOffset, c.records!.byteLength).equals(
          Buffer.from(want.buffer, want.byteOffset, want.byteLength),
        ),
      ).toBe(true);
    }
    expect(at).toBe(n);
    expect(r.warnings).toEqual([]);
    r.close();
    expect(m.HEAPU8.buffer.byteLength).toBeLessThan(512 << 20);
  });

  test('offset_to_point_data near 2^31 and a VLR count near 2^32 are refused before LASzip allocates or calls stdio', async () => {
    const m = await loadLasWasm();
    const heapBefore = m.HEAPU8.buffer.byteLength;
    for (const name of ['laspy_simple.las', 'laspy_simple.laz']) {
      const far = las(name);
      new DataView(far.buffer, far.byteOffset).setUint32(96, 0x7fff_ff00, true);
      expect((await lasRejects(far, `far-${name}`)).message).toMatch(
        /the point data is said to start at byte 2147483392, past the end of the file/,
      );
      await lasStillWorks();
      const vlrs = las(name);
      new DataView(vlrs.buffer, vlrs.byteOffset).setUint32(100, 0xffff_fff0, true);
      expect((await lasRejects(vlrs, `vlrs-${name}`)).message).toMatch(
        /announces 4294967280 variable-length records, but record \d+ does not fit/,
      );
      await lasStillWorks();
    }
    // LASzip's own VLR claiming more compressed items than it holds (LASzip read past it and trapped).
    const items = las('laspy_simple.laz');
    const at = Buffer.from(items).indexOf('laszip encoded');
    expect(at).toBeGreaterThan(0);
    new DataView(items.buffer, items.byteOffset).setUint16(at - 2 + 54 + 32, 32768, true);
    expect((await lasRejects(items, 'items.laz')).message).toMatch(
      /^items\.laz: corrupt LAZ header: the compression record \(\d+ bytes\) lists 32768 items/,
    );
    await lasStillWorks();
    expect(await loadLasWasm()).toBe(m); // nothing failed inside the module
    expect(m.HEAPU8.buffer.byteLength - heapBefore).toBeLessThan(64 << 20);
  });

  test('a LAZ chunk table that announces more chunks than points or bytes is refused before LASzip allocates for it', async () => {
    const m = await loadLasWasm();
    const heapBefore = m.HEAPU8.buffer.byteLength;
    const name = 'lazperf_autzen_trim.laz';
    const tableOf = (b: Uint8Array) => {
      const v = new DataView(b.buffer, b.byteOffset);
      return Number(v.getBigUint64(v.getUint32(96, true), true));
    };
    // 2^25 + 3: one flipped bit (the fuzz case: LASzip asked for 256 MiB, then read
    // /proc/meminfo through stdio, which this module does not have); 2^29: 8 bytes a
    // chunk wrap a 32-bit size to 8 bytes, and LASzip would write past them.
    for (const chunks of [2 ** 25 + 3, 2 ** 29, 0xffff_ffff]) {
      const b = las(name);
      new DataView(b.buffer, b.byteOffset).setUint32(tableOf(b) + 4, chunks, true);
      expect((await lasRejects(b, `chunks-${name}`)).message).toMatch(
        new RegExp(`corrupt LAZ file: the chunk table announces ${chunks} chunks for 110000 points`),
      );
      await lasStillWorks();
    }
    expect(await loadLasWasm()).toBe(m); // nothing failed inside the module
    expect(m.HEAPU8.buffer.byteLength - heapBefore).toBeLessThan(64 << 20);
  });

  test('impossible headers: count -1, NaN and zero scales, record length 0', async () => {
    const cases: [string, (dv: DataView) => void, RegExp][] = [
      ['count-1.las', (dv) => dv.setUint32(107, 0xffff_ffff, true), /truncated file: the header announces 4294967295 points/],
      ['nan-scale.las', (dv) => dv.setFloat64(131, NaN, true), /the x scale factor is nan \(it must be a finite, non-zero number\)/],
      ['zero-scale.laz', (dv) => dv.setFloat64(147, 0, true), /the z scale factor is 0 /],
      ['no-length.las', (dv) => dv.setUint16(105, 0, true), /the point record length is 0/],
    ];
    for (const [name, edit, message] of cases) {
      const bytes = las(name.endsWith('.laz') ? 'laspy_simple.laz' : 'laspy_simple.las');
      edit(new DataView(bytes.buffer, bytes.byteOffset));
      expect((await lasRejects(bytes, name)).message).toMatch(message);
      await lasStillWorks();
    }
    // A LAZ claiming 2^32-1 points (no truncation check is possible up front) fails where its data ends.
    const laz = las('laspy_simple.laz');
    new DataView(laz.buffer, laz.byteOffset).setUint32(107, 0xffff_ffff, true);
    expect((await lasRejects(laz, 'count-1.laz')).message).toMatch(/^count-1\.laz: cannot read point 1066 of 4294967295/);
    await expect(loadPointCloud(laz, 'count-1.laz')).rejects.toThrow(
      /^count-1\.laz: the file has 4,294,967,295 points .* more than this reader loads at once \(50,000,000\)/,
    );
    await lasStillWorks();
  });

  test('points outside the header bounds are warned about, in the reader, loadPointCloud and the CLI', async () => {
    for (const name of Object.keys(lasExpected)) {
      const pc = await loadPointCloud(las(name), name);
      expect(pc.warnings, name).toEqual([]);
    }
    const bytes = las('laspy_simple.las');
    const dv = new DataView(bytes.buffer, bytes.byteOffset);
    dv.setFloat64(179, dv.getFloat64(187, true) + 1, true); // max x = min x + 1 m
    const pc = await loadPointCloud(bytes, 'shrunk.las');
    expect(pc.count).toBe(1065);
    expect(pc.warnings).toHaveLength(1);
    expect(pc.warnings[0]).toMatch(/^shrunk\.las: [\d,]+ of 1,065 points lie outside the bounds the header gives/);
    const { writeFileSync, mkdtempSync, rmSync } = await import('node:fs');
    const { tmpdir } = await import('node:os');
    const dir = mkdtempSync(join(tmpdir(), 'hostile-las-'));
    const log = console.log;
    const error = console.error;
    const printed: string[] = [];
    try {
      writeFileSync(join(dir, 'shrunk.las'), bytes);
      console.log = () => undefined;
      console.error = (s: string) => printed.push(s);
      const r = (await lasCommand.run(
        { gpu: () => Promise.reject(new Error('no GPU')), log: () => undefined },
        { values: {}, positionals: [join(dir, 'shrunk.las')] },
      )) as {
        warnings: string[];
      };
      expect(r.warnings).toEqual(pc.warnings);
    } finally {
      console.log = log;
      console.error = error;
      rmSync(dir, { recursive: true, force: true });
    }
    expect(printed).toEqual([`warning: ${pc.warnings[0]}`]);
  });

  test('a trap in close() does not replace the result; the module is replaced for the next file', async () => {
    const m = await loadLasWasm();
    const close = m._las_close;
    m._las_close = () => {
      throw new WebAssembly.RuntimeError('null function or function signature mismatch');
    };
    try {
      const pc = await loadPointCloud(las('laspy_simple.laz'), 'trap-on-close.laz');
      expect(pc.count).toBe(1065);
    } finally {
      m._las_close = close;
    }
    expect(await loadLasWasm()).not.toBe(m);
    await lasStillWorks();
  });

  test('a trap while decoding becomes the reader error naming the file; the next file gets a fresh module', async () => {
    const m = await loadLasWasm();
    m._las_read = () => {
      throw new WebAssembly.RuntimeError('memory access out of bounds');
    };
    const e = await lasRejects(las('laspy_simple.laz'), 'trap.laz');
    expect(e.message).toBe('trap.laz: the file is corrupt in a way the LAS/LAZ decoder could not handle (memory access out of bounds)');
    expect(await loadLasWasm()).not.toBe(m);
    await lasStillWorks();
  });
});

// ---------------------------------------------------------------- TIFF

/** A classic little-endian TIFF: `pages` pages of width × height, one strip each of `stripBytes` bytes. */
function makeTiff(o: { width: number; height: number; bits: number; pages: number; compression?: number; stripBytes: number }): Uint8Array {
  const entries = 9;
  const ifdSize = 2 + 12 * entries + 4;
  const dataAt = 8 + ifdSize * o.pages;
  const bytes = new Uint8Array(dataAt + o.stripBytes * o.pages);
  const dv = new DataView(bytes.buffer);
  bytes.set([0x49, 0x49, 42, 0]);
  dv.setUint32(4, 8, true);
  for (let p = 0; p < o.pages; p++) {
    let at = 8 + p * ifdSize;
    dv.setUint16(at, entries, true);
    at += 2;
    const tags: [number, number, number][] = [
      [256, 4, o.width],
      [257, 4, o.height],
      [258, 3, o.bits],
      [259, 3, o.compression ?? 1],
      [262, 3, 1],
      [273, 4, dataAt + p * o.stripBytes],
      [277, 3, 1],
      [278, 4, o.height],
      [279, 4, o.stripBytes],
    ];
    for (const [tag, type, value] of tags) {
      dv.setUint16(at, tag, true);
      dv.setUint16(at + 2, type, true);
      dv.setUint32(at + 4, 1, true);
      if (type === 3) dv.setUint16(at + 8, value, true);
      else dv.setUint32(at + 8, value, true);
      at += 12;
    }
    dv.setUint32(at, p + 1 < o.pages ? 8 + (p + 1) * ifdSize : 0, true);
  }
  return bytes;
}

async function tiffRejects(run: () => Promise<unknown>, name: string): Promise<TiffError> {
  try {
    await run();
  } catch (e) {
    expect(e).toBeInstanceOf(TiffError);
    expect((e as Error).message.startsWith(`${name}: `)).toBe(true);
    return e as TiffError;
  }
  throw new Error(`${name} was accepted`);
}

describe('TIFF', () => {
  test('a 32768 × 65537 uint16 page (2^32 + 64 KiB) is refused with its size and the limit, never handed to _malloc', async () => {
    const m = await loadTiffWasm();
    const heapBefore = m.HEAPU8.buffer.byteLength;
    // The ImageJ stack (uint16) with its first directory's width and height set to 32768 × 65537.
    const bytes = hugeTiffPage(tif('imagejs_stack.tif'));
    const r = await TiffReader.open(bytes, 'huge.tif');
    expect([r.page(0).width, r.page(0).height, r.page(0).bitsPerSample]).toEqual([32768, 65537, 16]);
    const e = await tiffRejects(async () => r.readPage(0), 'huge.tif');
    r.close();
    expect(e.message).toMatch(
      /^huge\.tif: page 0: the page is 32768 x 65537 pixels of 1 x 16-bit samples \(4\.00 GiB\), more than the largest page this reader decodes \(1 GiB\)/,
    );
    const s = await tiffRejects(() => loadTiffStack({ name: 'huge.tif', bytes }), 'huge.tif');
    expect(s.message).toMatch(
      /the pages are 32768×65537 uint16 \(4\.00 GiB each\), more than the largest page this reader decodes \(1\.00 GiB\)/,
    );
    expect(m.HEAPU8.buffer.byteLength - heapBefore).toBeLessThan(16 << 20);
    expect(await loadTiffWasm()).toBe(m);
    await tiffStillWorks();
  });

  test('loadTiffStack allocates nothing from width × height × pages before the data backs it', async () => {
    // 13 pages of 16384 × 16384 bytes claimed (3.25 GiB) by a file of a few hundred bytes.
    for (const compression of [1, 8]) {
      const name = `claims-${compression}.tif`;
      const bytes = makeTiff({ width: 16384, height: 16384, bits: 8, pages: 13, compression, stripBytes: 4 });
      expect(bytes.length).toBeLessThan(2048);
      const before = process.memoryUsage().arrayBuffers;
      const e = await tiffRejects(() => loadTiffStack({ name, bytes }), name);
      expect(e.message).toMatch(
        compression === 1
          ? // libtiff cuts a single uncompressed strip into virtual strips of about 8 KiB; there is no room for them.
            /page 0: corrupt directory: 16384 strips claimed in a file of \d+ bytes/
          : /corrupt file: page 0 claims 16384×16384 uint8 \(256\.0 MiB\) from 4 B of compressed data/,
      );
      expect(process.memoryUsage().arrayBuffers - before).toBeLessThan(32 << 20);
      await tiffStillWorks();
    }
  });

  test('a trap inside libtiff becomes the reader error naming the file; the next file gets a fresh module', async () => {
    const m = await loadTiffWasm();
    m._tiff_read_page = () => {
      throw new WebAssembly.RuntimeError('memory access out of bounds');
    };
    const e = await tiffRejects(() => loadTiffStack({ name: 'trap.tif', bytes: tif('imagejs_stack.tif') }), 'trap.tif');
    expect(e.message).toBe('trap.tif: the file is corrupt in a way the TIFF decoder could not handle (memory access out of bounds)');
    expect(await loadTiffWasm()).not.toBe(m);
    await tiffStillWorks();
  });

  test('a trap in close() does not replace the result', async () => {
    const m = await loadTiffWasm();
    m._tiff_close = () => {
      throw new WebAssembly.RuntimeError('null function or function signature mismatch');
    };
    const v = await loadTiffStack({ name: 'imagejs_stack.tif', bytes: tif('imagejs_stack.tif') });
    expect(v.dims).toEqual([128, 128, 10]);
    expect(await loadTiffWasm()).not.toBe(m);
    await tiffStillWorks();
  });
});
