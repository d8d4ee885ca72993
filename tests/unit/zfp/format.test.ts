// The format layer against zfp's own files: header fields of every vector, the
// header we write, zfp's rate -> bits-per-block rule (fractional rates, and the
// 148-bit header of rates above 32), and every malformed input rejected with
// its reason. Also the CPU reference codec against the vectors (fast, no GPU).
import { mkdtempSync, readFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { describe, expect, it } from 'vitest';
import { decodeVolume, encodeVolume, toWords } from '../../../src/zfp/cpu/codec.ts';
import { bitsPerBlockForRate, openZfpStream, planZfpStream, ZfpFormatError } from '../../../src/zfp/format.ts';
import { parseZfpHeader, writeZfpHeader } from '../../../src/zfp/header.ts';
import { describeFile } from '../../../src/formats/describe.ts';
import { runPython } from '../../helpers/python.ts';
import { firstDifference, readVector, vectors } from './vectors.ts';

const hex = (b: Uint8Array) => Buffer.from(b).toString('hex');

describe('zfp header and stream description', () => {
  it('parses every vector as zfp 1.0.1 wrote it', () => {
    for (const v of vectors) {
      const withHeader = readVector(v.with_header.file);
      const h = parseZfpHeader(withHeader);
      expect(h.scalarType).toBe('float32');
      expect(h.dimensionality).toBe(3);
      expect(h.size.slice(0, 3)).toEqual(v.dims_xyz);
      expect(h.mode).toMatchObject({ kind: 'fixed-rate', maxBits: v.bits_per_block, minBits: v.bits_per_block });
      expect(h.headerBits).toBe(96);
      const info = openZfpStream(withHeader, v.with_header.file);
      expect(info).toMatchObject({
        dims: v.dims_xyz,
        rate: v.rate,
        bitsPerBlock: v.bits_per_block,
        blockCount: v.nblocks,
        payloadBitOffset: 96,
        paddedBytes: v.with_header.bytes,
      });
      const bare = readVector(v.compressed);
      expect(openZfpStream(bare, v.compressed)).toMatchObject({
        dims: v.dims_xyz,
        rate: v.rate,
        payloadBitOffset: 0,
        paddedBytes: bare.byteLength,
      });
      // the header we write is zfp's
      expect(hex(writeZfpHeader(v.dims_xyz, v.bits_per_block).bytes)).toBe(v.header_hex);
    }
  });

  it("computes bits per block like zfp_stream_set_rate, and reads zfp's 148-bit header above rate 32", () => {
    const rates = [0.1328125, 0.5, 1, 1.3, 2.71, 3.3, 4.0078125, 7.77, 10.01, 15.5, 31.99, 32, 33, 40.3, 63.9];
    const out = runPython(
      `
import sys, json, numpy as np, zfpy
a = np.random.default_rng(3).random((5, 6, 7)).astype(np.float32)
res = []
for r in json.loads(sys.argv[1]):
    c = zfpy.compress_numpy(a, rate=r, write_header=True)
    res.append(c[:24].hex())
print(json.dumps(res))
`,
      [JSON.stringify(rates)],
    );
    const heads: string[] = JSON.parse(out);
    rates.forEach((rate, i) => {
      const head = new Uint8Array(Buffer.from(heads[i], 'hex'));
      const h = parseZfpHeader(head);
      const bits = bitsPerBlockForRate(rate);
      expect(h.mode.kind, `rate ${rate}`).toBe('fixed-rate');
      expect(h.mode.maxBits, `rate ${rate}`).toBe(bits);
      expect(h.headerBits, `rate ${rate}`).toBe(bits > 2048 ? 148 : 96);
      // our header is bit for bit zfpy's (the 148-bit one shares its last byte with block 0)
      const ours = writeZfpHeader([7, 6, 5], bits);
      const n = Math.floor(ours.bits / 8);
      expect(hex(ours.bytes.subarray(0, n)), `rate ${rate}`).toBe(hex(head.subarray(0, n)));
      const mask = (1 << (ours.bits % 8)) - 1;
      if (mask) expect(ours.bytes[n] & mask).toBe(head[n] & mask);
    });
  });

  describe('rejects malformed input with its reason', () => {
    const dir = mkdtempSync(join(tmpdir(), 'zfp-format-'));
    runPython(
      `
import sys, numpy as np, zfpy
d = sys.argv[1]
a = np.random.default_rng(5).random((9, 10, 11)).astype(np.float32)
open(d + '/precision.zfp', 'wb').write(zfpy.compress_numpy(a, precision=8, write_header=True))
open(d + '/accuracy.zfp', 'wb').write(zfpy.compress_numpy(a, tolerance=0.01, write_header=True))
open(d + '/plane.zfp', 'wb').write(zfpy.compress_numpy(a[0], rate=4, write_header=True))
open(d + '/double.zfp', 'wb').write(zfpy.compress_numpy(a.astype(np.float64), rate=4, write_header=True))
open(d + '/int32.zfp', 'wb').write(zfpy.compress_numpy((a * 1000).astype(np.int32), rate=8, write_header=True))
open(d + '/rate4.zfp', 'wb').write(zfpy.compress_numpy(a, rate=4, write_header=True))
`,
      [dir],
    );
    const file = (name: string) => new Uint8Array(readFileSync(join(dir, name)));
    const good = file('rate4.zfp');
    const patched = (edit: (b: Uint8Array) => void) => {
      const b = good.slice();
      edit(b);
      return b;
    };
    // header with 65536^3 (sizes - 1 = 0xffff in each 16-bit field)
    const absurd = patched((b) => {
      const meta = (((0xffffn << 32n) | (0xffffn << 16n) | 0xffffn) << 4n) | (2n << 2n) | 2n;
      for (let i = 0; i < 52; i++) {
        const bit = 32 + i;
        b[bit >> 3] = (b[bit >> 3] & ~(1 << (bit & 7))) | (Number((meta >> BigInt(i)) & 1n) << (bit & 7));
      }
    });
    // mode 2176: reversible
    const reversible = patched((b) => {
      const mode = 2176;
      b[10] = (b[10] & 0x0f) | ((mode & 0xf) << 4);
      b[11] = mode >> 4;
    });
    const cases: [string, Uint8Array, string, RegExp][] = [
      ['fixed precision', file('precision.zfp'), 'p.zfp', /p\.zfp: the zfp stream is fixed precision 8, not fixed-rate/],
      ['fixed accuracy', file('accuracy.zfp'), 'a.zfp', /a\.zfp: the zfp stream is fixed accuracy .*, not fixed-rate/],
      ['reversible', reversible, 'r.zfp', /r\.zfp: the zfp stream is reversible \(lossless\), not fixed-rate/],
      ['2D', file('plane.zfp'), 'plane.zfp', /plane\.zfp: the zfp header describes a 2D field \(11x10\); only 3D/],
      ['float64', file('double.zfp'), 'd.zfp', /d\.zfp: the zfp stream holds float64 values; only float32/],
      ['int32', file('int32.zfp'), 'i.zfp', /i\.zfp: the zfp stream holds int32 values; only float32/],
      [
        'wrong magic',
        patched((b) => (b[2] = 0x71)),
        'x.zfp',
        /x\.zfp: no zfp header \(the file does not start with "zfp"\) and the name carries no shape/,
      ],
      ['wrong codec version', patched((b) => (b[3] = 4)), 'v.zfp', /v\.zfp: zfp codec version 4 is not supported/],
      [
        'truncated',
        good.subarray(0, good.byteLength - 9),
        't.zfp',
        /t\.zfp: truncated: the header promises 11x10x9 float32 at 256 bits per block \(27 blocks\), 876 bytes with the header, but the file has 871 bytes/,
      ],
      ['a bare header', good.subarray(0, 12), 'h.zfp', /h\.zfp: truncated/],
      ['shorter than a header', good.subarray(0, 7), 's.zfp', /s\.zfp: the file is 7 bytes, shorter than a zfp header/],
      ['absurd size', absurd, 'big.zfp', /big\.zfp: absurd size 65536x65536x65536 in the zfp header: 4\.398e\+12 blocks/],
      [
        'headerless without rate',
        readVector(vectors[0].compressed).subarray(0),
        'vol_64x64x64_float32.zfp',
        /no zfp header and no rate: give the rate \(--rate R\).*\(the size fits rate 2\)/,
      ],
      [
        'headerless of the wrong size',
        readVector(vectors[0].compressed).subarray(8),
        'vol_64x64x64_float32.raw.crate2.zfp',
        /a header-less fixed-rate 2 stream of 64x64x64 float32 is 65536 bytes .* but the file has 65528: truncated, or not a fixed-rate stream/,
      ],
      [
        'fixed precision without header',
        new Uint8Array(5008),
        'fuel_64x64x64_float8.zfp',
        /no fixed rate gives 5008 bytes for 64x64x64, so this is not a fixed-rate stream/,
      ],
      [
        'headerless float64',
        readVector(vectors[0].compressed),
        'vol_64x64x64_float64.raw.crate2.zfp',
        /the name says float64; only float32/,
      ],
      ['headerless absurd name', new Uint8Array(64), 'vol_0x64x64_float32.raw.crate2.zfp', /absurd size 0x64x64 in the file name/],
      [
        'rate below 9 bits per block',
        new Uint8Array(64),
        'vol_8x8x8_float32.raw.crate0.1.zfp',
        /rate 0\.1 gives 6 bits per block, fewer than the 9 a float32 block needs/,
      ],
    ];
    for (const [what, bytes, name, message] of cases) {
      it(what, () => {
        let error: unknown;
        try {
          openZfpStream(bytes, name);
        } catch (e) {
          error = e;
        }
        expect(error).toBeInstanceOf(ZfpFormatError);
        expect((error as Error).message).toMatch(message);
        // `cli info` reports the same problem
        expect(describeFile(name, bytes.byteLength, bytes.subarray(0, 64)).problems.join('\n')).toMatch(message);
      });
    }
    it('the compressor refuses what zfp could not decode block by block', () => {
      expect(() => planZfpStream('v.raw', [8, 8, 8], 0.1, true)).toThrow(/6 bits per block/);
      expect(() => planZfpStream('v.raw', [70000, 4, 4], 4, true)).toThrow(/a zfp header holds sizes up to 65536/);
      expect(planZfpStream('v.raw', [70000, 4, 4], 4, false).bitsPerBlock).toBe(256);
    });
  });
});

describe('CPU reference codec (twin of the WGSL)', () => {
  it('decodes and encodes every vector bit for bit', () => {
    for (const v of vectors) {
      for (const file of [v.compressed, v.with_header.file]) {
        const bytes = readVector(file);
        const info = openZfpStream(bytes, file);
        const decoded = decodeVolume(toWords(bytes), info.dims, info.bitsPerBlock, info.payloadBitOffset);
        expect(firstDifference(new Uint8Array(decoded.buffer), readVector(v.decoded)), file).toBe('identical');
        const input = new Float32Array(readVector(v.input).buffer);
        const words = new Uint32Array(info.paddedBytes / 4 + 1);
        if (info.hasHeader) new Uint8Array(words.buffer).set(writeZfpHeader(info.dims, info.bitsPerBlock).bytes);
        encodeVolume(input, info.dims, info.bitsPerBlock, words, info.payloadBitOffset);
        expect(firstDifference(new Uint8Array(words.buffer, 0, info.paddedBytes), bytes), file).toBe('identical');
      }
    }
  });
});
