// LAS/LAZ through LASzip compiled to Wasm, against laspy (+lazrs): the shared
// files' expected.json, and LAS 1.4 files written by laspy in the test.
import { createHash } from 'node:crypto';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, test } from 'vitest';
import { LasError, LasReader, loadLasWasm, loadPointCloud, scaled, type LasHeader } from '../../../src/loaders/las.ts';
import { makeFixtures, readBytes, sharedData, sharedExpected, type Fixtures } from './fixtures.ts';

const expected = sharedExpected('las');
const names = Object.keys(expected);

interface Decoded {
  header: LasHeader;
  xyz: Int32Array;
  positions: Float32Array;
  rgb?: Uint16Array;
  intensity: Uint16Array;
  classification: Uint8Array;
  recordsSha256: string;
}

/** Reads every field of every point, in chunks of `chunk`. */
async function decodeAll(bytes: Uint8Array, name: string, chunk = 40_000): Promise<Decoded> {
  const reader = await LasReader.open(bytes, name);
  try {
    const n = reader.header.pointCount;
    const out = {
      xyz: new Int32Array(n * 3),
      positions: new Float32Array(n * 3),
      rgb: reader.header.hasRGB ? new Uint16Array(n * 3) : undefined,
      intensity: new Uint16Array(n),
      classification: new Uint8Array(n),
    };
    const hash = createHash('sha256');
    const fields = { xyz: true, positions: true, rgb: true, intensity: true, classification: true, records: true };
    for (;;) {
      const c = reader.read(chunk, fields, { ...out, offset: reader.pointsRead });
      if (!c) break;
      hash.update(c.records!);
    }
    expect(reader.pointsRead).toBe(n);
    return { header: reader.header, ...out, recordsSha256: hash.digest('hex') };
  } finally {
    reader.close();
  }
}

describe('shared LAS/LAZ files match laspy (expected.json)', () => {
  const decoded = new Map<string, Decoded>();
  beforeAll(async () => {
    for (const name of names) decoded.set(name, await decodeAll(readBytes(join(sharedData, 'las', name)), name));
  });

  test.each(names)('%s: header, first points, bounds and every record', (name) => {
    const e = expected[name];
    const d = decoded.get(name)!;
    const h = d.header;
    expect(h.pointCount).toBe(e.point_count);
    expect(h.version).toBe(e.las_version);
    expect(h.pointFormat).toBe(e.point_format);
    expect(h.pointRecordLength).toBe(e.point_record_length);
    expect(h.compressed).toBe(e.compressed_laz);
    expect(h.hasRGB).toBe(e.has_rgb);
    expect(h.hasGpsTime).toBe(e.has_gps_time);
    expect(h.vlrCount).toBe(e.num_vlrs); // both leave out LASzip's own VLR
    expect(h.scale).toEqual(e.scales);
    expect(h.offset.map((o) => o + 0)).toEqual(e.offsets.map((o: number) => o + 0)); // -0 vs 0
    for (let a = 0; a < 3; a++) {
      expect(h.bounds.min[a]).toBeCloseTo(e.bounds_header.min[a], 6);
      expect(h.bounds.max[a]).toBeCloseTo(e.bounds_header.max[a], 6);
    }
    // The first points, as integers and scaled in float64 (bit-exact like laspy).
    for (let i = 0; i < 3; i++) {
      expect([d.xyz[3 * i], d.xyz[3 * i + 1], d.xyz[3 * i + 2]]).toEqual(e.first3_XYZ_int[i]);
      expect([0, 1, 2].map((a) => scaled(h, a as 0 | 1 | 2, d.xyz[3 * i + a]))).toEqual(e.first3_xyz_scaled[i]);
      if (e.has_rgb) expect([d.rgb![3 * i], d.rgb![3 * i + 1], d.rgb![3 * i + 2]]).toEqual(e.first3_rgb[i]);
    }
    // Bounds over all points.
    const min = [Infinity, Infinity, Infinity];
    const max = [-Infinity, -Infinity, -Infinity];
    for (let i = 0; i < h.pointCount; i++)
      for (let a = 0; a < 3; a++) {
        const v = scaled(h, a as 0 | 1 | 2, d.xyz[3 * i + a]);
        min[a] = Math.min(min[a], v);
        max[a] = Math.max(max[a], v);
      }
    expect(min).toEqual(e.bounds_points.min);
    expect(max).toEqual(e.bounds_points.max);
    // Every record, re-serialized in LAS layout: proves the LAZ decode is exact.
    expect(d.recordsSha256).toBe(e.points_record_sha256);
  });

  test('positions are float32 offsets from the centre of the header bounds', () => {
    for (const name of names) {
      const d = decoded.get(name)!;
      const h = d.header;
      for (let a = 0; a < 3; a++) expect(h.centre[a]).toBe((h.bounds.min[a] + h.bounds.max[a]) / 2);
      let worst = 0;
      for (let i = 0; i < h.pointCount * 3; i++) {
        const a = (i % 3) as 0 | 1 | 2;
        const exact = scaled(h, a, d.xyz[i]) - h.centre[a];
        // float32 rounding of a value relative to the centre: within one ulp.
        worst = Math.max(worst, Math.abs(d.positions[i] - exact) / Math.max(Math.abs(exact) * 2 ** -23, 1e-12));
      }
      expect(worst, name).toBeLessThanOrEqual(1);
    }
    // UTM-sized coordinates keep centimetres: autzen's positions are within ±600 m.
    const autzen = decoded.get('lazperf_autzen_trim.laz')!;
    expect(autzen.positions.reduce((m, v) => Math.max(m, Math.abs(v)), 0)).toBeLessThan(600);
  });

  test('a .laz and its .las twin decode to identical arrays', () => {
    for (const [las, laz] of [
      ['laspy_simple.las', 'laspy_simple.laz'],
      ['lazperf_autzen_trim.las', 'lazperf_autzen_trim.laz'],
      ['lazperf_point10.las', 'lazperf_point10.las.laz'],
    ]) {
      const a = decoded.get(las)!;
      const b = decoded.get(laz)!;
      expect(Buffer.from(a.positions.buffer).equals(Buffer.from(b.positions.buffer)), las).toBe(true);
      expect(Buffer.from(a.intensity.buffer).equals(Buffer.from(b.intensity.buffer)), las).toBe(true);
      expect(Buffer.from(a.classification.buffer).equals(Buffer.from(b.classification.buffer)), las).toBe(true);
      if (a.rgb) expect(Buffer.from(a.rgb.buffer).equals(Buffer.from(b.rgb!.buffer)), las).toBe(true);
    }
  });
});

describe('streaming a point cloud in chunks', () => {
  test('loadPointCloud reports progress per chunk and fills the arrays in order', async () => {
    const bytes = readBytes(join(sharedData, 'las', 'lazperf_autzen_trim.laz'));
    const progress: number[] = [];
    const starts: number[] = [];
    const pc = await loadPointCloud(bytes, 'autzen.laz', {
      chunkSize: 25_000,
      onProgress: (done, total) => {
        expect(total).toBe(110_000);
        progress.push(done);
      },
      onChunk: (c) => starts.push(c.start),
      yieldBetweenChunks: true,
    });
    expect(progress).toEqual([25_000, 50_000, 75_000, 100_000, 110_000]);
    expect(starts).toEqual([0, 25_000, 50_000, 75_000, 100_000]);
    expect(pc.count).toBe(110_000);
    expect(pc.rgb?.length).toBe(330_000);
    // Same arrays as a one-chunk read.
    const whole = await loadPointCloud(bytes, 'autzen.laz', { chunkSize: 1 << 20 });
    expect(Buffer.from(pc.positions.buffer).equals(Buffer.from(whole.positions.buffer))).toBe(true);
    expect(Buffer.from(pc.rgb!.buffer).equals(Buffer.from(whole.rgb!.buffer))).toBe(true);
    const e = expected['lazperf_autzen_trim.laz'];
    for (let a = 0; a < 3; a++) {
      expect(pc.localBounds.min[a] + pc.header.centre[a]).toBeCloseTo(e.bounds_points.min[a], 3);
      expect(pc.localBounds.max[a] + pc.header.centre[a]).toBeCloseTo(e.bounds_points.max[a], 3);
    }
  });
});

describe('opening a Blob (a dropped File)', () => {
  test('streams it into the heap and decodes the same points', async () => {
    const bytes = readBytes(join(sharedData, 'las', 'lazperf_autzen_trim.laz'));
    const seen: number[] = [];
    const r = await LasReader.open(new Blob([bytes]), 'autzen.laz', (done, total) => {
      expect(total).toBe(bytes.byteLength);
      seen.push(done);
    });
    const a = r.read(1 << 20, { records: true })!;
    r.close();
    expect(seen[seen.length - 1]).toBe(bytes.byteLength);
    const b = await decodeAll(bytes, 'autzen.laz');
    expect(createHash('sha256').update(a.records!).digest('hex')).toBe(b.recordsSha256);
  });
});

describe('LAS 1.4 point formats 6, 7, 8 written by laspy/lazrs', () => {
  let fx: Fixtures;
  beforeAll(() => {
    fx = makeFixtures();
  });
  afterAll(() => fx?.dispose());

  test('every record, RGB and extended classification match laspy', async () => {
    const files = Object.keys(fx.expected.las);
    expect(files.length).toBe(6);
    for (const name of files) {
      const e = fx.expected.las[name];
      const d = await decodeAll(readBytes(join(fx.dir, name)), name, 1234);
      expect(d.header.version, name).toBe('1.4');
      expect(d.header.pointFormat, name).toBe(e.point_format);
      expect(d.header.pointCount, name).toBe(e.point_count);
      expect(d.header.pointRecordLength, name).toBe(e.point_record_length);
      expect(d.header.hasRGB, name).toBe(e.point_format >= 7);
      for (let i = 0; i < 3; i++) {
        expect([d.xyz[3 * i], d.xyz[3 * i + 1], d.xyz[3 * i + 2]], name).toEqual(e.first3_XYZ_int[i]);
        if (e.first3_rgb) expect([d.rgb![3 * i], d.rgb![3 * i + 1], d.rgb![3 * i + 2]], name).toEqual(e.first3_rgb[i]);
      }
      expect([...d.classification.slice(0, 5)], name).toEqual(e.classification);
      expect([...d.intensity.slice(0, 5)], name).toEqual(e.intensity);
      // Classes above 31 exist only in the extended formats; the generator uses 0-63.
      expect(Math.max(...d.classification), name).toBeGreaterThan(31);
      expect(d.recordsSha256, name).toBe(e.points_record_sha256);
    }
  });
});

describe('bad files', () => {
  const autzenLas = () => readBytes(join(sharedData, 'las', 'lazperf_autzen_trim.las'));
  const autzenLaz = () => readBytes(join(sharedData, 'las', 'lazperf_autzen_trim.laz'));

  async function failure(bytes: Uint8Array, name: string, readAll = true): Promise<LasError> {
    try {
      const pc = readAll
        ? await loadPointCloud(bytes, name)
        : await LasReader.open(bytes, name).then((r) => {
            r.close();
            return r;
          });
      throw new Error(`expected ${name} to fail, got ${'count' in pc ? pc.count : 0} points`);
    } catch (e) {
      expect(e).toBeInstanceOf(LasError);
      return e as LasError;
    }
  }

  test('not a LAS file, empty, and garbage after the signature', async () => {
    expect((await failure(new TextEncoder().encode('hello, not a point cloud'), 'notes.las')).message).toMatch(
      /^notes\.las: not a LAS\/LAZ file/,
    );
    expect((await failure(new Uint8Array(0), 'empty.laz')).message).toMatch(/^empty\.laz: not a LAS\/LAZ file/);
    const garbage = new Uint8Array(60).fill(0xff);
    garbage.set([0x4c, 0x41, 0x53, 0x46]);
    expect((await failure(garbage, 'garbage.las')).message).toMatch(/^garbage\.las: /);
  });

  test('truncated LAS and LAZ files', async () => {
    const las = await failure(autzenLas().slice(0, 1_000_000), 'cut.las');
    expect(las.message).toMatch(/^cut\.las: truncated file: the header announces 110000 points/);
    const header = await failure(autzenLas().slice(0, 150), 'header-cut.las');
    expect(header.message).toMatch(/^header-cut\.las: truncated file: 150 bytes, shorter than a LAS header \(227 bytes\)/);
    for (const cut of [200_000, 602_000]) {
      const laz = await failure(autzenLaz().slice(0, cut), `cut${cut}.laz`);
      expect(laz.message).toMatch(new RegExp(`^cut${cut}\\.laz: cannot read point \\d+ of 110000 \\(truncated or corrupt point data\\)`));
    }
  });

  test('corrupt compressed data fails cleanly or decodes, never crashes', async () => {
    const bytes = autzenLaz();
    // Scramble the middle of the compressed points.
    for (let i = 300_000; i < 300_400; i++) bytes[i] ^= 0x5a;
    try {
      const pc = await loadPointCloud(bytes, 'scrambled.laz');
      expect(pc.count).toBe(110_000); // arithmetic decoding of noise yields (wrong) points
    } catch (e) {
      expect(e).toBeInstanceOf(LasError);
      expect((e as Error).message).toMatch(/^scrambled\.laz: /);
    }
  });

  test('Wasm memory is released after every file, good or bad', async () => {
    const m = await loadLasWasm();
    const good = autzenLas();
    const bad = good.slice(0, 2_000_000);
    const laz = autzenLaz().slice(0, 400_000);
    // Warm up: the heap grows to its working size once.
    await loadPointCloud(good, 'a.las');
    await failure(bad, 'b.las');
    const heap = m.HEAPU8.length;
    for (let i = 0; i < 25; i++) {
      await loadPointCloud(good, 'a.las', { chunkSize: 10_000 + i });
      await failure(bad, 'b.las');
      await failure(laz, 'c.laz');
      const r = await LasReader.open(good, 'd.las');
      r.read(5000, { positions: true, records: true, xyz: true });
      r.close();
    }
    // 25 leaked copies of a 3.7 MB file would have grown the heap by ~90 MB.
    expect(m.HEAPU8.length).toBe(heap);
  });

  test('a closed reader refuses to read', async () => {
    const r = await LasReader.open(autzenLas(), 'x.las');
    r.close();
    expect(() => r.read(10)).toThrow(/x\.las: the reader is closed/);
    r.close(); // twice is fine
  });
});
