// `cli render` (issue 46): a figure and each pixel's hit distance, headless.
// A sphere's distance field written by NumPy, compressed at rate 16 on load
// (the GPU encoder writes zfpy's bytes: tests/unit/zfp/encoder.test.ts):
//   - rays: on a third of the covered pixels (and some of the background), the depth equals NumPy's exact first
//     crossing of the trilinear interpolant of zfpy's decode along the
//     pixel's ray (per cell the cubic fitted exactly through 4 points,
//     numpy.roots), within 0.02 voxel (the depth buffer's float32 bounds it:
//     the distance comes from the stored depth), and the analytic sphere
//     within 0.05 voxel (the sampling and the codec's error);
//   (rays against the mesh, and the exact crossing on published volumes:
//   ray-layer.test.ts);
//   - the PNG is a PNG (zlib over its IDAT, in Python) of the size asked.
import { spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, describe, expect, it } from 'vitest';
import { repoRoot, runPython } from '../../helpers/python.ts';

const work = mkdtempSync(join(tmpdir(), 'render-cli-'));
afterAll(() => rmSync(work, { recursive: true, force: true }));

function cli(...args: string[]) {
  const r = spawnSync(
    process.execPath,
    ['--import', join(repoRoot, 'scripts/register-node-loaders.mjs'), join(repoRoot, 'src/cli/main.ts'), ...args],
    { encoding: 'utf8', timeout: 240_000 },
  );
  return { status: r.status, stderr: r.stderr };
}

const N = 40;
const CENTRE = [19.3, 20.1, 18.7];
const RADIUS = 11.2;
const ISO = 0;

describe('cli render', () => {
  it('rays: the exact trilinear crossing per pixel (NumPy), the analytic sphere; a PNG', () => {
    const raw = join(work, `sphere_${N}x${N}x${N}_float32.raw`);
    runPython(
      `
import sys, numpy as np
n = ${N}
z, y, x = np.mgrid[0:n, 0:n, 0:n].astype(np.float64)
f = ${RADIUS} - np.sqrt((x - ${CENTRE[0]}) ** 2 + (y - ${CENTRE[1]}) ** 2 + (z - ${CENTRE[2]}) ** 2)
f.astype(np.float32).tofile(sys.argv[1])
`,
      [raw],
    );
    const run = (draw: 'rays' | 'mesh') => {
      const r = cli(
        'render',
        raw,
        '--iso',
        String(ISO),
        '--rate',
        '16',
        '--draw',
        draw,
        '--size',
        '96x72',
        '--png',
        join(work, `${draw}.png`),
        '--depth',
        join(work, `${draw}.f32`),
        '--json',
        join(work, `${draw}.json`),
      );
      expect(r.status, r.stderr).toBe(0);
      return {
        record: JSON.parse(readFileSync(join(work, `${draw}.json`), 'utf8')),
        depth: new Float32Array(new Uint8Array(readFileSync(join(work, `${draw}.f32`))).buffer),
      };
    };
    const rays = run('rays');
    expect(rays.record).toMatchObject({ draw: 'rays', size: [96, 72], level0Fraction: 1, levels: [0] });
    expect(rays.record.coveredPixels).toBeGreaterThan(200);
    expect(rays.depth.length).toBe(96 * 72);

    // NumPy: the first crossing of the pixels' rays, exactly (every third covered pixel and some of the background), and the PNG read back
    const pixels: [number, number][] = [];
    for (let y = 0; y < 72; y++) {
      for (let x = 0; x < 96; x++) {
        const covered = Number.isFinite(rays.depth[y * 96 + x]);
        if ((covered && (x + 96 * y) % 3 === 0) || (!covered && (x + 96 * y) % 211 === 0)) pixels.push([x, y]);
      }
    }
    const out = JSON.parse(
      runPython(
        `
import sys, json, zlib, struct, zfpy, numpy as np
n, W, H, iso = ${N}, 96, 72, ${ISO}
a = np.fromfile(sys.argv[1], dtype=np.float32).reshape(n, n, n)
v = zfpy.decompress_numpy(zfpy.compress_numpy(a, rate=16)).astype(np.float64)   # z, y, x
rec = json.load(open(sys.argv[2]))
inv = np.array(rec['inverseViewProjection'], dtype=np.float64).reshape(4, 4).T   # column-major
eye = np.array(rec['eye'])
def unproject(x, y, z):
    p = inv @ np.array([(x + 0.5) / W * 2 - 1, 1 - (y + 0.5) / H * 2, z, 1.0])
    return p[:3] / p[3]
def tri(c, q):
    f = q - c
    s = 0.0
    for k in range(8):
        o = [(k >> a) & 1 for a in range(3)]
        w = np.prod([f[a] if o[a] else 1 - f[a] for a in range(3)])
        s += w * v[c[2] + o[2], c[1] + o[1], c[0] + o[0]]
    return s - iso
def first_hit(o, d):
    t_in, t_out = 0.0, 1.0
    for a in range(3):
        if d[a] == 0: continue
        t0, t1 = (0 - o[a]) / d[a], (n - 1 - o[a]) / d[a]
        t_in, t_out = max(t_in, min(t0, t1)), min(t_out, max(t0, t1))
    if not t_in < t_out: return None
    step = 0.05 / np.linalg.norm(d)
    seen = None
    t = t_in
    while t <= t_out:
        c = np.minimum(np.floor(o + t * d).astype(int), n - 2)
        c = np.maximum(c, 0)
        key = tuple(c)
        if key != seen:
            seen = key
            lo, hi = t_in, t_out
            for a in range(3):
                if d[a] == 0: continue
                ta, tb = (c[a] - o[a]) / d[a], (c[a] + 1 - o[a]) / d[a]
                lo, hi = max(lo, min(ta, tb)), min(hi, max(ta, tb))
            if hi > lo:
                ss = np.linspace(0, 1, 4)
                g = [tri(c, o + (lo + s * (hi - lo)) * d) for s in ss]
                coeffs = np.polyfit(ss, g, 3)
                roots = [r.real for r in np.roots(coeffs) if abs(r.imag) < 1e-9 and -1e-9 <= r.real <= 1 + 1e-9]
                if g[0] == 0: roots.append(0.0)
                if roots:
                    s = min(roots)
                    return o + (lo + s * (hi - lo)) * d
        t += step
    return None
exact = []
for x, y in json.loads(sys.argv[4]):
    o, f = unproject(x, y, 0.0), unproject(x, y, 1.0)
    p = first_hit(o, f - o)
    exact.append([x, y, None if p is None else float(np.linalg.norm(p - eye)), None if p is None else float(np.linalg.norm(p - np.array(${JSON.stringify(CENTRE)})))])
png = open(sys.argv[3], 'rb').read()
assert png[:8] == b'\\x89PNG\\r\\n\\x1a\\n'
w, h = struct.unpack('>II', png[16:24])
pos, idat = 8, b''
while pos < len(png):
    length, = struct.unpack('>I', png[pos:pos + 4]); kind = png[pos + 4:pos + 8]
    if kind == b'IDAT': idat += png[pos + 8:pos + 8 + length]
    assert zlib.crc32(png[pos + 4:pos + 8 + length]) == struct.unpack('>I', png[pos + 8 + length:pos + 12 + length])[0]
    pos += 12 + length
pixels = len(zlib.decompress(idat))
print(json.dumps({'exact': exact, 'png': [w, h, pixels]}))
`,
        [raw, join(work, 'rays.json'), join(work, 'rays.png'), JSON.stringify(pixels)],
      ),
    );
    expect(out.png).toEqual([96, 72, 72 * (1 + 4 * 96)]);
    let hits = 0;
    for (const [x, y, distance, fromCentre] of out.exact as [number, number, number | null, number | null][]) {
      const ours = rays.depth[y * 96 + x];
      if (distance === null) {
        expect(ours, `pixel ${x}, ${y}: no crossing`).toBe(Number.POSITIVE_INFINITY);
        continue;
      }
      hits++;
      expect(Math.abs(ours - distance), `pixel ${x}, ${y}`).toBeLessThan(0.02);
      expect(Math.abs(fromCentre! - RADIUS), `pixel ${x}, ${y}: on the sphere`).toBeLessThan(0.05);
    }
    expect(hits).toBeGreaterThan(60);
  });
});
