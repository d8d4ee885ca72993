// One test per class of hostile file found by issue 13 (non-Wasm readers):
// lying names, gzip bombs and damaged gzip in NRRD, absurd header sizes,
// NaN/Inf volumes (page path, CLI, GPU block ranges), SWC trees that are not
// trees; and a file after a rejected file always opens.
import { spawnSync } from 'node:child_process';
import { mkdtempSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { gzipSync } from 'node:zlib';
import { describe, expect, it } from 'vitest';
import { describeFile } from '../../../src/formats/describe.ts';
import { Isosurface } from '../../../src/isosurface/isosurface.ts';
import { checkSwcTree, parseSwc, SwcError } from '../../../src/loaders/swc.ts';
import { NrrdError, NRRD_MAX_DATA_BYTES, parseNrrd } from '../../../src/volume/nrrd.ts';
import { checkValueRange, inspectVolumeFile, openVolumeBytes, VolumeFileError } from '../../../src/volume/open-volume.ts';
import { blockRanges, decodeVolume, toWords } from '../../../src/zfp/cpu/codec.ts';
import { ZfpEncoder } from '../../../src/zfp/encoder.ts';
import { ZfpFormatError } from '../../../src/zfp/format.ts';
import { gzipBomb } from '../../fuzz/mutators.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { repoRoot } from '../../helpers/python.ts';

const f32bytes = (a: Float32Array) => new Uint8Array(a.buffer, a.byteOffset, a.byteLength);

function nrrd(lines: string[], payload: Uint8Array): Uint8Array {
  const head = new TextEncoder().encode(['NRRD0004', ...lines, '', ''].join('\n'));
  const out = new Uint8Array(head.length + payload.length);
  out.set(head);
  out.set(payload, head.length);
  return out;
}

/** A float32 ramp over 9x6x5 (values 0..269). */
function ramp(): Float32Array {
  return Float32Array.from({ length: 9 * 6 * 5 }, (_, i) => i);
}

function cli(...args: string[]) {
  const r = spawnSync(
    process.execPath,
    ['--import', join(repoRoot, 'scripts/register-node-loaders.mjs'), join(repoRoot, 'src/cli/main.ts'), ...args],
    {
      encoding: 'utf8',
      timeout: 240_000,
    },
  );
  return { status: r.status, stderr: r.stderr, stdout: r.stdout };
}

async function rejection(p: Promise<unknown>): Promise<Error> {
  const e = await p.then(
    () => undefined,
    (x: unknown) => x,
  );
  if (!(e instanceof Error)) throw new Error(`expected a rejection, got ${String(e)}`);
  return e;
}

describe('lying names', () => {
  const stream = new Uint8Array(512); // the name decides what these bytes should be
  it(".crate0 is the zfp reader's error naming the file (page, CLI, `cli info`)", async () => {
    const name = 'v_4x4x4_float32.raw.crate0.zfp';
    const e = await rejection(inspectVolumeFile(name, stream));
    expect(e).toBeInstanceOf(ZfpFormatError);
    expect(e.message).toMatch(/^v_4x4x4_float32\.raw\.crate0\.zfp: the rate in the file name \(0\) is not a positive number/);
    const info = describeFile(name, stream.length, stream);
    expect(info.problems.join(' ')).toMatch(/crate0\.zfp: the rate in the file name \(0\)/);
  });

  it('huge, zero and impossible dims in the name are rejected before any allocation', async () => {
    for (const name of [
      'v_99999999999999999999x2x2_float32.raw',
      'v_0x4x4_uint8.raw',
      'v_65537x65537x65537_float32.raw.crate8.zfp',
      'v_0x4x4_float32.raw.crate8.zfp',
    ]) {
      const e = await rejection(inspectVolumeFile(name, stream));
      expect(e instanceof VolumeFileError || e instanceof ZfpFormatError, `${name}: ${e.name}`).toBe(true);
      expect(e.message.startsWith(`${name}: `)).toBe(true);
      expect(() => describeFile(name, stream.length, stream)).not.toThrow();
    }
    // An empty file named with a zero dimension: 0 bytes "fit" 0x4x4, still refused.
    const empty = await rejection(inspectVolumeFile('v_0x4x4_uint8.raw', new Uint8Array(0)));
    expect(empty.message).toMatch(/the shape 0x4x4 in the name is impossible/);
  });

  it('`cli info` on a .crate0 name prints the problem and exits 0', () => {
    const dir = mkdtempSync(join(tmpdir(), 'hostile-'));
    const path = join(dir, 'v_4x4x4_float32.raw.crate0.zfp');
    writeFileSync(path, stream);
    const r = cli('info', path);
    expect(r.stderr).not.toMatch(/RangeError|TypeError/);
    expect(r.status).toBe(0);
    expect(r.stdout).toMatch(/problems .*crate0\.zfp: the rate in the file name \(0\)/);
  });
});

describe('NRRD gzip', () => {
  it('a 1 MB gzip bomb under a small header inflates only what the header announces', async () => {
    const bomb = gzipBomb();
    expect(bomb.length).toBeLessThan(2 ** 21);
    const file = nrrd(['type: uchar', 'dimension: 3', 'sizes: 64 64 64', 'encoding: gzip'], bomb);
    const before = process.memoryUsage();
    const t0 = performance.now();
    const v = await parseNrrd(file);
    const ms = performance.now() - t0;
    const after = process.memoryUsage();
    expect(v.data.length).toBe(64 ** 3);
    expect(v.data.every((x) => x === 0)).toBe(true);
    // Before the fix: 1 GiB inflated, 3.2 GiB peak, 10-16 s.
    expect(after.arrayBuffers - before.arrayBuffers).toBeLessThan(64 << 20);
    expect(ms).toBeLessThan(5000);
  });

  it("damaged gzip is the reader's error naming the file", async () => {
    const data = new Uint8Array(2 * 3 * 4).fill(7);
    const gz = gzipSync(data);
    const cases: [string, Uint8Array, RegExp][] = [
      ['not-gzip.nrrd', data, /the gzip data is damaged after 0 of 24 bytes \(.*(incorrect header check|invalid).*\)/i],
      [
        'cut.nrrd',
        gz.subarray(0, gz.length - 12),
        /the gzip data is damaged after \d+ of 24 bytes \(.*(unexpected end|end of file|incomplete).*\)/i,
      ],
    ];
    for (const [name, payload, message] of cases) {
      const file = nrrd(['type: uchar', 'dimension: 3', 'sizes: 2 3 4', 'encoding: gzip'], payload);
      await expect(parseNrrd(file)).rejects.toBeInstanceOf(NrrdError);
      const e = await rejection(inspectVolumeFile(name, file));
      expect(e).toBeInstanceOf(VolumeFileError);
      expect(e.message.startsWith(`${name}: `)).toBe(true);
      expect(e.message).toMatch(message);
    }
  });

  it('absurd sizes give the number and the limit, before any allocation', async () => {
    const file = nrrd(['type: float', 'dimension: 3', 'sizes: 100000 100000 100000', 'encoding: gzip'], gzipSync(new Uint8Array(16)));
    const e = await rejection(parseNrrd(file));
    expect(e.message).toBe(
      `100000x100000x100000 float32 is 4000000000000000 bytes of samples, more than the ${NRRD_MAX_DATA_BYTES} bytes (4 GiB) this reader takes`,
    );
    const huge = nrrd(['type: float', 'dimension: 3', 'sizes: 1e300 1 1', 'encoding: raw'], new Uint8Array(16));
    await expect(parseNrrd(huge)).rejects.toThrow(/more than the 4294967296 bytes/);
  });
});

describe('NaN and Inf', () => {
  gpuTest(
    'raw float32 with NaN/Inf: replaced before compression, counted in a notice; the value range is the finite one',
    async ({ gpu }) => {
      const v = ramp();
      v[3] = NaN;
      v[100] = Infinity;
      v[101] = -Infinity;
      v[269] = NaN; // the largest finite value becomes 268
      const opened = await openVolumeBytes(gpu.device, f32bytes(v), 'nan_9x6x5_float32.raw', { rate: 32 });
      expect(opened.nonFinite).toMatchObject({ values: 270, nan: 2, posInf: 1, negInf: 1, finiteMin: 0, finiteMax: 268 });
      expect(opened.notes).toEqual([
        'nan_9x6x5_float32.raw: 4 of 270 values are not finite (2 NaN, 1 +Inf, 1 -Inf); zfp cannot store NaN or Inf, so before compressing NaN and -Inf became the smallest finite value (0, outside every surface) and +Inf became the largest (268)',
      ]);
      const iso = await Isosurface.create(gpu, opened.stream);
      try {
        // rate 32: zfp is near-lossless here; the range is the finite one (0..268), not [0, 0] or NaN
        const [lo, hi] = checkValueRange(opened.fileName, iso.info.valueRange);
        expect(lo).toBeCloseTo(0, 3);
        expect(hi).toBeCloseTo(268, 3);
        const stats = await iso.compute(134);
        expect(stats.triangles).toBeGreaterThan(0);
      } finally {
        iso.destroy();
        opened.stream.destroy();
      }
    },
  );

  gpuTest('an all-NaN or all-Inf volume is refused with a clear message; float64 beyond float32 counts as Inf', async ({ gpu }) => {
    for (const fill of [NaN, Infinity, -Infinity]) {
      const e = await rejection(openVolumeBytes(gpu.device, f32bytes(new Float32Array(270).fill(fill)), 'bad_9x6x5_float32.raw'));
      expect(e).toBeInstanceOf(VolumeFileError);
      expect(e.message).toMatch(
        /^bad_9x6x5_float32\.raw: all 270 values are NaN or infinite \(270 (NaN|\+Inf|-Inf)\): there is no value range/,
      );
    }
    const f64 = Float64Array.from(ramp());
    f64[5] = 1e300;
    const opened = await openVolumeBytes(gpu.device, new Uint8Array(f64.buffer), 'big_9x6x5_float64.raw');
    expect(opened.nonFinite).toMatchObject({ posInf: 1, finiteMax: 269 });
    opened.stream.destroy();
  });

  gpuTest('NRRD float with NaN takes the same path as raw', async ({ gpu }) => {
    const v = ramp();
    v.fill(NaN, 0, 10);
    const opened = await openVolumeBytes(
      gpu.device,
      nrrd(['type: float', 'dimension: 3', 'sizes: 9 6 5', 'encoding: raw', 'endian: little'], f32bytes(v)),
      'n.nrrd',
    );
    expect(opened.notes[0]).toMatch(/^n\.nrrd: 10 of 270 values are not finite \(10 NaN\)/);
    opened.stream.destroy();
  });

  gpuTest(
    'a zfp file that decodes to Inf/NaN: the GPU block ranges skip them, as the CPU reference does; no finite value is refused',
    async ({ gpu }) => {
      // 12x4x4 = 3 blocks at rate 8 (512 bits each, header-less). Block 1's bits all set: a non-zero
      // block with the largest exponent, whose values overflow float32.
      const dims: [number, number, number] = [12, 4, 4];
      const enc = await ZfpEncoder.create(gpu.device);
      const values = Float32Array.from({ length: 12 * 16 }, (_, i) => Math.sin(i));
      const { bytes } = await enc.compress(f32bytes(values), 'float32', dims, 8, { header: false });
      enc.destroy();
      bytes.fill(0xff, 64, 128);
      const decoded = decodeVolume(toWords(bytes), dims, 512);
      const nonFinite = decoded.filter((x) => !Number.isFinite(x)).length;
      expect(nonFinite, 'the damaged block decodes to non-finite values').toBeGreaterThan(0);
      const reference = blockRanges(decoded, dims);
      const opened = await openVolumeBytes(gpu.device, bytes, 'inf_12x4x4_float32.raw.crate8.zfp');
      const iso = await Isosurface.create(gpu, opened.stream);
      try {
        const ranges = await iso.readBlockRanges();
        expect([...ranges]).toEqual([...reference]);
        expect(ranges.every((x) => Number.isFinite(x))).toBe(true);
        const [lo, hi] = checkValueRange(opened.fileName, iso.info.valueRange);
        const finite = decoded.filter((x) => Number.isFinite(x));
        expect([lo, hi]).toEqual([Math.min(...finite), Math.max(...finite)]);
      } finally {
        iso.destroy();
        opened.stream.destroy();
      }
      // No finite value at all: every block gets the empty range [FLT_MAX, -FLT_MAX], and so does the volume.
      const FLT_MAX = 3.4028234663852886e38;
      expect(() => checkValueRange('inf.zfp', [FLT_MAX, -FLT_MAX])).toThrow(/^inf\.zfp: the volume has no finite values/);
      expect(() => checkValueRange('inf.zfp', [Infinity, -Infinity])).toThrow(VolumeFileError);
    },
  );

  it('`cli extract` on an all-NaN volume exits 1 with the message; with some NaN it prints the notice and a finite range', () => {
    const dir = mkdtempSync(join(tmpdir(), 'hostile-'));
    const allNan = join(dir, 'nan_9x6x5_float32.raw');
    writeFileSync(allNan, f32bytes(new Float32Array(270).fill(NaN)));
    const bad = cli('extract', allNan, '--iso', '1');
    expect(bad.status).toBe(1);
    expect(bad.stderr).toMatch(/nan_9x6x5_float32\.raw: all 270 values are NaN or infinite/);
    const some = ramp();
    some[7] = NaN;
    const path = join(dir, 'some_9x6x5_float32.raw');
    writeFileSync(path, f32bytes(some));
    const json = join(dir, 'out.json');
    const ok = cli('extract', path, '--iso', '100', '--rate', '16', '--json', json);
    expect(ok.status, ok.stderr).toBe(0);
    expect(ok.stderr).toMatch(/note: some_9x6x5_float32\.raw: 1 of 270 values are not finite \(1 NaN\)/);
    const result = JSON.parse(spawnSync('cat', [json], { encoding: 'utf8' }).stdout);
    expect(result.valueRange.every((x: unknown) => typeof x === 'number')).toBe(true);
    expect(result.notes).toHaveLength(1);
  });
});

describe('SWC trees that are not trees', () => {
  const swc = (lines: string[]) => parseSwc(lines.join('\n'), 'n.swc');
  it('self-parents: found, their link dropped, the rest drawn', () => {
    const t = swc(['1 1 0 0 0 1 -1', '2 3 1 0 0 1 1', '3 3 2 0 0 1 3']);
    expect(t.problems).toEqual(['1 sample is its own parent (id 3); not linked']);
    expect([...t.parentIndex]).toEqual([-1, 0, -1]);
  });
  it('cycles: found with their samples, their links dropped, the valid tree drawn', () => {
    const t = swc(['1 1 0 0 0 1 -1', '2 3 1 0 0 1 1', '3 3 2 0 0 1 5', '4 3 3 0 0 1 3', '5 3 4 0 0 1 4', '6 3 5 0 0 1 5']);
    expect(t.problems).toEqual(['1 parent cycle (3 samples, id 3, 5, 4); their links are not drawn']);
    expect([...t.parentIndex]).toEqual([-1, 0, -1, -1, -1, 4]);
    expect(checkSwcTree(t)).toMatchObject({ cycles: 1, cycleSamples: 3, roots: 1, drawnSegments: 2 });
  });
  it('missing root and dangling parents are said', () => {
    const t = swc(['1 1 0 0 0 1 7', '2 3 1 0 0 1 1', '3 3 2 0 0 1 2']);
    expect(t.problems).toEqual([
      '1 sample names a parent that is not in the file (id 1); drawn unlinked',
      'no root (no sample has parent -1)',
    ]);
    expect([...t.parentIndex]).toEqual([-1, 0, 1]);
  });
  it('a sound tree has no problems', () => {
    const t = swc(['1 1 0 0 0 1 -1', '2 3 1 0 0 1 1', '3 3 2 0 0 1 2', '4 3 2 1 0 1 2']);
    expect(t.problems).toEqual([]);
    expect(checkSwcTree(t)).toMatchObject({ selfParents: 0, cycles: 0, danglingParents: 0, roots: 1, drawnSegments: 3 });
  });
  it('malformed lines are SwcErrors naming file and line', () => {
    expect(() => parseSwc('1 1 0 0 0 1 -1\n2 3 x 0 0 1 1\n', 'bad.swc')).toThrow(SwcError);
    expect(() => parseSwc('1 1 0 0 0 1 -1\n2 3 x 0 0 1 1\n', 'bad.swc')).toThrow(/^bad\.swc, line 2: x "x" is not a number$/);
  });
});

describe('a file after a rejected file opens correctly', () => {
  gpuTest('zfp, raw and NRRD, in one session (one device, one encoder)', async ({ gpu }) => {
    const v = ramp();
    const enc = await ZfpEncoder.create(gpu.device);
    const { bytes: zfp } = await enc.compress(f32bytes(v), 'float32', [9, 6, 5], 8, { header: true });
    enc.destroy();
    const good: [string, Uint8Array][] = [
      ['ok.zfp', zfp],
      ['ok_9x6x5_float32.raw', f32bytes(v)],
      ['ok.nrrd', nrrd(['type: float', 'dimension: 3', 'sizes: 9 6 5', 'encoding: gzip', 'endian: little'], gzipSync(f32bytes(v)))],
    ];
    const bad: [string, Uint8Array][] = [
      ['bad.zfp', zfp.slice(0, 40)],
      ['v_4x4x4_float32.raw.crate0.zfp', new Uint8Array(64)],
      ['bad_9x6x5_float32.raw', f32bytes(new Float32Array(270).fill(NaN))],
      ['bad.nrrd', nrrd(['type: float', 'dimension: 3', 'sizes: 9 6 5', 'encoding: gzip'], gzipSync(f32bytes(v)).subarray(0, 30))],
      ['bomb.nrrd', nrrd(['type: float', 'dimension: 3', 'sizes: 9 6 5', 'encoding: gzip'], gzipBomb())],
    ];
    for (const [badName, badBytes] of bad) {
      for (const [name, bytes] of good) {
        const e = await openVolumeBytes(gpu.device, badBytes, badName).then(
          (o) => {
            o.stream.destroy();
            return undefined;
          },
          (x: unknown) => x,
        );
        // bomb.nrrd is all zeros: a valid (constant) volume of the announced size.
        if (badName !== 'bomb.nrrd')
          expect(e instanceof VolumeFileError || e instanceof ZfpFormatError, `${badName}: ${String(e)}`).toBe(true);
        const opened = await openVolumeBytes(gpu.device, bytes, name);
        expect(opened.dims).toEqual([9, 6, 5]);
        opened.stream.destroy();
      }
    }
  });
});
