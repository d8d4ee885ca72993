// A constant chunk's zfp stream (what an absent Zarr chunk holds: its
// array's fill value) made on the CPU equals zfpy's, byte for byte, for
// short and long headers, rates that are not whole bits, and awkward values.
import { describe, expect, it } from 'vitest';
import { constantChunkStream } from '../../../src/zfp/cpu/constant-stream.ts';
import { runPython } from '../../helpers/python.ts';

const cases: Array<[number, number, number]> = [
  [16, 8, 0],
  [16, 8, 3.5],
  [32, 4, -1e-20],
  [8, 1.5, 123456.789],
  [4, 40, -0.1],
  [64, 0.25, 2.5e30],
];

describe('constantChunkStream', () => {
  it("equals zfpy's stream of a constant C^3 chunk (header included)", () => {
    const ref = JSON.parse(
      runPython(
        `
import sys, json, zfpy, numpy as np
out = []
for c, rate, v in json.loads(sys.argv[1]):
    out.append(zfpy.compress_numpy(np.full((c, c, c), v, np.float32), rate=rate, write_header=True).hex())
print(json.dumps(out))
`,
        [JSON.stringify(cases)],
      ),
    ) as string[];
    cases.forEach(([c, rate, v], i) => {
      expect(Buffer.from(constantChunkStream(c, rate, v)).toString('hex'), `${c}^3 at rate ${rate}, value ${v}`).toBe(ref[i]);
    });
  });
});
