// Chunks that arrive as values (stores of lossless chunks) are encoded on
// the GPU straight into their pool slot (ZfpEncoder.encodeSlot through
// ChunkedVolume.put): each slot must hold exactly zfpy's stream of that chunk
// (header included), whatever the slot's place (slots straddle the 256-byte
// binding alignment, pools of several shards), and encoding one slot must
// leave its neighbours as they were, including a slot used before by
// another chunk. Random values, awkward chunk edges and rates.
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, describe, expect } from 'vitest';
import { readBuffer } from '../../../src/gpu/buffers.ts';
import { ChunkedVolume, type ChunkLevelLayout } from '../../../src/zfp/chunked-volume.ts';
import { encoderFor } from '../../../src/zfp/encoder.ts';
import { planZfpStream } from '../../../src/zfp/format.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { runPython } from '../../helpers/python.ts';

const work = mkdtempSync(join(tmpdir(), 'encode-slot-'));
afterAll(() => rmSync(work, { recursive: true, force: true }));

/** zfpy's streams of `count` chunks of edge^3 float32 values (x fastest) at `rate`, concatenated. */
function zfpyStreams(values: Float32Array, edge: number, count: number, rate: number): Uint8Array {
  const input = join(work, `in-${edge}-${rate}.f32`);
  const output = join(work, `out-${edge}-${rate}.bin`);
  writeFileSync(input, values);
  runPython(
    `
import sys, numpy as np, zfpy
e, n, rate = int(sys.argv[3]), int(sys.argv[4]), float(sys.argv[5])
a = np.fromfile(sys.argv[1], dtype=np.float32).reshape(n, e, e, e)
open(sys.argv[2], 'wb').write(b''.join(zfpy.compress_numpy(c, rate=rate, write_header=True) for c in a))
`,
    [input, output, String(edge), String(count), String(rate)],
  );
  return new Uint8Array(readFileSync(output));
}

function randomChunks(edge: number, count: number, seed: number): Float32Array {
  const out = new Float32Array(edge ** 3 * count);
  let s = seed >>> 0;
  for (let i = 0; i < out.length; i++) {
    s = (Math.imul(s, 1664525) + 1013904223) >>> 0;
    // smooth-ish with noise and a few large magnitudes (exponents vary between blocks)
    out[i] = Math.sin(i / 37) * 100 + ((s >>> 8) / 2 ** 24 - 0.5) * (i % 97 === 0 ? 1e4 : 3);
  }
  return out;
}

describe('ZfpEncoder.encodeSlot through ChunkedVolume.put', () => {
  for (const [edge, rate, shardSlots] of [
    [4, 3, 5],
    [8, 1, 3],
    [12, 8, 4],
    [16, 16, 2],
  ] as const) {
    gpuTest(`${edge}^3 chunks at rate ${rate}: every slot = zfpy's stream of its chunk; neighbours untouched`, async ({ gpu }) => {
      const count = 7;
      const chunkBytes = planZfpStream('chunk', [edge, edge, edge], rate, true).paddedBytes;
      const layout: ChunkLevelLayout = {
        dims: [edge * count, edge, edge],
        chunkEdge: edge,
        chunkGrid: [count, 1, 1],
        rate,
        chunkBytes,
        name: `test ${edge}^3`,
        arrivesAs: 'float32',
      };
      const encoder = await encoderFor(gpu.device);
      const pool = ChunkedVolume.create(gpu, layout, { poolChunks: count, encoder, maxShardBytes: shardSlots * chunkBytes + 4 });
      expect(pool.shards.length).toBe(Math.ceil(count / shardSlots));
      const values = randomChunks(edge, count, edge * 1000 + rate);
      const expected = zfpyStreams(values, edge, count, rate);
      const chunkValues = (c: number) => new Uint8Array(values.buffer, c * edge ** 3 * 4, edge ** 3 * 4);
      // a slot first holds another chunk, which leaves: the next chunk's stream must not keep its bits
      pool.put(6, chunkValues(6));
      pool.evict(6);
      for (const c of [3, 0, 5, 1, 6, 2, 4]) pool.put(c, chunkValues(c));
      for (let c = 0; c < count; c++) {
        const slot = pool.slotOfChunk(c)!;
        const shard = pool.shards.find((s) => slot >= s.firstSlot && slot < s.endSlot)!;
        const got = new Uint8Array(await readBuffer(gpu.device, shard.buffer, (slot - shard.firstSlot) * chunkBytes, chunkBytes));
        expect(got, `chunk ${c} in slot ${slot}`).toEqual(expected.subarray(c * chunkBytes, (c + 1) * chunkBytes));
      }
      expect(() => pool.put(0, new Uint8Array(16))).toThrow(
        /test \d+\^3 chunk \(0, 0, 0\): 16 bytes of values, a \d+\^3 float32 chunk has/,
      );
      pool.destroy();
    });
  }
});
