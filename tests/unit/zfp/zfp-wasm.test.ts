// zfp's C decoder compiled to WebAssembly (wasm/dist/zfp.*, src/loaders/zfp-wasm.ts):
// every fixed-rate test vector (rates 2, 4, 8, 16; block-aligned and partial
// border blocks), with and without zfp's header, decodes bit for bit to
// zfpy's output (zfp-vectors/*.decoded.raw); the header facts are read; and
// streams it cannot decode are refused with a message instead of aborting.
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { describe, expect, test } from 'vitest';
import { decodeZfpWasm, decodeZfpWasmRaw, ZfpWasmError, ZfpWasmStream } from '../../../src/loaders/zfp-wasm.ts';
import { SHARED_DATA } from '../mc/reference.ts';

const DIR = join(SHARED_DATA, 'zfp-vectors');

interface Vector {
  name: string;
  dims_xyz: [number, number, number];
  rate: number;
  bits_per_block: number;
  compressed: string;
  decoded: string;
  with_header: { file: string };
}

const vectors: Vector[] = JSON.parse(readFileSync(join(DIR, 'manifest.json'), 'utf8')).vectors;
const bytes = (file: string) => new Uint8Array(readFileSync(join(DIR, file)));

function expectBitExact(got: Float32Array, file: string): void {
  const want = bytes(file);
  expect(got.byteLength).toBe(want.byteLength);
  const g = new Uint8Array(got.buffer, got.byteOffset, got.byteLength);
  let firstDiff = -1;
  for (let i = 0; i < g.length && firstDiff < 0; i++) if (g[i] !== want[i]) firstDiff = i;
  expect(firstDiff, `${file}: first differing byte`).toBe(-1);
}

describe('zfp C decoder in Wasm = zfpy', () => {
  test('there are vectors at rates 2, 4, 8 and 16, some with partial blocks', () => {
    expect(new Set(vectors.map((v) => v.rate))).toEqual(new Set([2, 4, 8, 16]));
    expect(vectors.some((v) => v.dims_xyz.some((n) => n % 4 !== 0))).toBe(true);
  });

  for (const v of vectors) {
    test(`${v.with_header.file}: header and bit-exact decode`, async () => {
      const s = await ZfpWasmStream.load(bytes(v.with_header.file), v.with_header.file);
      try {
        expect(s.info).toEqual({ dims: v.dims_xyz, type: 3, dimensionality: 3, mode: 2, bitsPerBlock: v.bits_per_block, headerBits: 96 });
        s.decode();
        expectBitExact(s.output().slice(), v.decoded);
        // A second decode of the same stream gives the same field.
        s.decode();
        expectBitExact(s.output().slice(), v.decoded);
      } finally {
        s.free();
      }
    });

    test(`${v.compressed} (header-less, rate ${v.rate}): bit-exact decode`, async () => {
      expectBitExact(await decodeZfpWasmRaw(bytes(v.compressed), v.dims_xyz, v.rate), v.decoded);
    });
  }

  test('a shared volume: the bonsai at rate 4 decodes to what zfpy gives (mc.json hash)', async () => {
    const file = join(SHARED_DATA, 'volumes', 'bonsai_256x256x256_float32.rate4.zfp');
    const out = await decodeZfpWasm(new Uint8Array(readFileSync(file)), 'bonsai');
    const { createHash } = await import('node:crypto');
    const mc = JSON.parse(readFileSync(join(SHARED_DATA, 'reference', 'mc.json'), 'utf8'));
    const entry = mc.volumes.find((x: { file: string }) => x.file.endsWith('bonsai_256x256x256_float32.rate4.zfp'));
    expect(
      createHash('sha256')
        .update(new Uint8Array(out.buffer, out.byteOffset, out.byteLength))
        .digest('hex'),
    ).toBe(entry.decoded_sha256);
  });

  test('refuses what it cannot decode, with a message', async () => {
    const good = bytes(vectors[0].with_header.file);
    await expect(decodeZfpWasm(new Uint8Array(8))).rejects.toThrow(/shorter than zfp's 96-bit header/);
    const badMagic = good.slice();
    badMagic[0] = 0x41;
    await expect(decodeZfpWasm(badMagic)).rejects.toThrow(ZfpWasmError);
    await expect(decodeZfpWasm(badMagic)).rejects.toThrow(/no valid zfp header/);
    await expect(decodeZfpWasm(good.slice(0, good.length >> 1))).rejects.toThrow(/truncated/);
    const v = vectors[0];
    await expect(decodeZfpWasmRaw(bytes(v.compressed).slice(0, 100), v.dims_xyz, v.rate)).rejects.toThrow(
      /shorter than the shape and rate need/,
    );
  });
});
