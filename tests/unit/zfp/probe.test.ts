// VolumeProbe against zfpy: the trilinear value at random points (and at
// the volume's corners and edges, where cells are clamped) of a published
// zfp stream equals NumPy's trilinear interpolation of zfpy's decode of it.
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { describe, expect } from 'vitest';
import { loadZfpStream } from '../../../src/zfp/gpu-stream.ts';
import { VolumeProbe } from '../../../src/zfp/probe.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { runPython, sharedData } from '../../helpers/python.ts';

describe('VolumeProbe', () => {
  gpuTest('trilinear values of the decoded volume, as NumPy over zfpy', async ({ gpu }) => {
    const file = join(sharedData, 'volumes/hydrogen_atom_128x128x128_float32.rate8.zfp');
    const stream = loadZfpStream(gpu.device, new Uint8Array(readFileSync(file)), file);
    const probe = await VolumeProbe.create(gpu.device);
    let seed = 7;
    const rnd = () => 40 + ((seed = (seed * 16807) % 2147483647) / 2147483647) * 48; // around the atom
    const points: [number, number, number][] = [
      [0, 0, 0],
      [127, 127, 127],
      [126.5, 0.25, 127],
      [63.5, 64.25, 62.75],
      ...Array.from({ length: 12 }, () => [rnd(), rnd(), rnd()] as [number, number, number]),
    ];
    const ours = await Promise.all(points.map((p) => probe.sample(stream, p)));
    const numpy = JSON.parse(
      runPython(
        `
import sys, json, zfpy, numpy as np
v = zfpy.decompress_numpy(open(sys.argv[1], 'rb').read()).astype(np.float64)   # z, y, x
n = v.shape[::-1]
out = []
for p in json.loads(sys.argv[2]):
    lo = [min(max(int(np.floor(p[a])), 0), n[a] - 2) for a in range(3)]
    f = [min(max(p[a] - lo[a], 0), 1) for a in range(3)]
    s = 0.0
    for k in range(8):
        c = [lo[a] + ((k >> a) & 1) for a in range(3)]
        w = np.prod([f[a] if (k >> a) & 1 else 1 - f[a] for a in range(3)])
        s += w * v[c[2], c[1], c[0]]
    out.append(s)
print(json.dumps(out))
`,
        [file, JSON.stringify(points)],
      ),
    );
    ours.forEach((v, i) => expect(v, `point ${points[i].join(', ')}`).toBeCloseTo(numpy[i], 4));
    expect(new Set(numpy.map((x: number) => x.toFixed(3))).size).toBeGreaterThan(8); // not a constant field
    probe.destroy();
    stream.destroy();
  });
});
