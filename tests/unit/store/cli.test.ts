import { mkdtempSync, readdirSync, readFileSync, rmSync, statSync, truncateSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, it } from 'vitest';
import { sharedData } from '../../helpers/python.ts';
import { cli, convert, converterPython } from './stores.ts';

const work = mkdtempSync(join(tmpdir(), 'store-cli-'));
const store = join(work, 'bonsai.zarr');
const oneStream = join(work, 'bonsai_256x256x256_float32.rate4.zfp');

/** Bytes of every file of the range arrays (metadata and chunks). */
function rangeBytes(root: string): number {
  let total = 0;
  const walk = (dir: string) => {
    for (const e of readdirSync(dir, { withFileTypes: true })) {
      if (e.isDirectory()) walk(join(dir, e.name));
      else total += statSync(join(dir, e.name)).size;
    }
  };
  walk(join(root, 'ranges'));
  return total;
}

/** NumPy over level 0 (argv[1]: the store): per 32^3 chunk its range (lo, hi) and nb(), the 27-neighbourhood reduction. */
const CHUNK_NEIGHBOURHOODS = `
import sys, zarr, numpy as np
v = zarr.open_array(sys.argv[1] + '/0', mode='r')[:]     # z, y, x
c = 32
g = [n // c for n in v.shape]
blocks = v.reshape(g[0], c, g[1], c, g[2], c)
lo, hi = blocks.min(axis=(1, 3, 5)), blocks.max(axis=(1, 3, 5))
def nb(a, f, fill):
    p = np.pad(a, 1, constant_values=fill)
    out = a.copy()
    for dz in range(3):
        for dy in range(3):
            for dx in range(3):
                out = f(out, p[dz:dz + g[0], dy:dy + g[1], dx:dx + g[2]])
    return out
`;

beforeAll(() => {
  convert('volumes/bonsai_256x256x256_float32.rate4.zfp', store, ['--chunk', '32', '--rate', '4', '--shard', '2']);
  // the converter's input: bonsai decoded by zfpy; the same volume as one stream at rate 4
  converterPython(
    `
import sys, zfpy, numpy as np
a = zfpy.decompress_numpy(open(sys.argv[1], 'rb').read())
open(sys.argv[2], 'wb').write(zfpy.compress_numpy(np.ascontiguousarray(a, dtype=np.float32), rate=4, write_header=True))
`,
    [join(sharedData, 'volumes/bonsai_256x256x256_float32.rate4.zfp'), oneStream],
  );
}, 900_000);
afterAll(() => rmSync(work, { recursive: true, force: true }));

describe('CLI on stores', () => {
  it('extract --level 0 --iso a,b,c: drawn together, the in-core triangles, the chunks any surface needs fetched once', () => {
    const isos = '40.5,90,150';
    const a = cli('extract', store, '--level', '0', '--iso', isos, '--json', join(work, 'store.json'));
    expect(a.status, a.stderr).toBe(0);
    const b = cli('extract', oneStream, '--iso', isos, '--json', join(work, 'incore.json'));
    expect(b.status, b.stderr).toBe(0);
    const s = JSON.parse(readFileSync(join(work, 'store.json'), 'utf8'));
    const c = JSON.parse(readFileSync(join(work, 'incore.json'), 'utf8'));
    expect(s.dims).toEqual([256, 256, 256]);
    // the store's three surfaces in one refinement, from the same resident chunks
    expect(s.drawnTogether).toEqual([40.5, 90, 150]);
    const tri = (r: { isosurfaces: { triangles: number }[] }) => r.isosurfaces.map((x) => x.triangles);
    expect(tri(s)).toEqual(tri(c));
    // the same triangles, summed in another order (only the chunks fetched are in the pool)
    s.isosurfaces.forEach((x: { surfaceArea: number }, i: number) =>
      expect(Math.abs(x.surfaceArea / c.isosurfaces[i].surfaceArea - 1)).toBeLessThan(1e-12),
    );
    expect(s.isosurfaces[0].triangles).toBeGreaterThan(10_000);
    const chunkBytes = 12 + 8 ** 3 * 32 + 4; // 32^3 at rate 4: 512 blocks of 256 bits, header padded
    const needed = Number(
      converterPython(
        `${CHUNK_NEIGHBOURHOODS}
nlo, nhi = nb(lo, np.minimum, np.inf), nb(hi, np.maximum, -np.inf)
need = np.zeros(lo.shape, bool)
for iso in [np.float32(x) for x in sys.argv[2].split(',')]:
    need |= (nlo < iso) & (iso <= nhi)
print(int(need.sum()))
`,
        [store, isos],
      ),
    );
    expect(needed).toBeGreaterThan(0);
    expect(needed).toBeLessThan(512);
    expect(s.store).toMatchObject({ level: 0, chunks: needed, levelChunks: 512, chunkBytesFetched: needed * chunkBytes });
    // + metadata (zarr.json of the group, the levels, the range arrays), the range arrays' chunks and at most 64 shard indexes (8 x 16 + 4 bytes each)
    expect(s.store.bytesFetched).toBeGreaterThan(s.store.chunkBytesFetched + s.store.metadataBytes);
    expect(s.store.bytesFetched).toBeLessThanOrEqual(
      s.store.chunkBytesFetched + s.store.metadataBytes + rangeBytes(store) + 64 * (8 * 16 + 4),
    );
  });

  it('extract --clip: chunks the box removes whole are not fetched; the same clipped triangles as in-core', () => {
    const box = '40,0,10,150,256,200';
    const a = cli('extract', store, '--level', '0', '--iso', '90', '--clip', box, '--json', join(work, 'clip-store.json'));
    expect(a.status, a.stderr).toBe(0);
    const b = cli('extract', oneStream, '--iso', '90', '--clip', box, '--json', join(work, 'clip-incore.json'));
    expect(b.status, b.stderr).toBe(0);
    const s = JSON.parse(readFileSync(join(work, 'clip-store.json'), 'utf8'));
    const c = JSON.parse(readFileSync(join(work, 'clip-incore.json'), 'utf8'));
    expect(s.isosurfaces[0].clippedTriangles).toBe(c.isosurfaces[0].clippedTriangles);
    expect(s.isosurfaces[0].clippedTriangles).toBeGreaterThan(1000);
    // NumPy: chunks the surface needs (27-neighbourhood ranges), split by whether the box meets their cells (one voxel of slack)
    const [kept, clipped] = JSON.parse(
      converterPython(
        `${CHUNK_NEIGHBOURHOODS}
import json
iso = np.float32(90)
need = (nb(lo, np.minimum, np.inf) < iso) & (iso <= nb(hi, np.maximum, -np.inf))
b = [float(x) for x in sys.argv[2].split(',')]
gz, gy, gx = np.meshgrid(*[np.arange(n) for n in g], indexing='ij')
meets = np.ones(need.shape, bool)
for a, gi in enumerate([gx, gy, gz]):
    meets &= ((gi + 1) * c + 1 > b[a]) & (gi * c - 1 < b[a + 3])
print(json.dumps([int((need & meets).sum()), int((need & ~meets).sum())]))
`,
        [store, box],
      ),
    );
    expect(clipped).toBeGreaterThan(0);
    expect(s.store).toMatchObject({ chunks: kept, clippedChunks: clipped });
  });

  it('bench --level 1 runs on the level; a damaged chunk is reported naming it', () => {
    const r = cli('bench', store, '--level', '1', '--count', '3', '--modes', 'random', '--json', join(work, 'bench.json'));
    expect(r.status, r.stderr).toBe(0);
    const b = JSON.parse(readFileSync(join(work, 'bench.json'), 'utf8'));
    expect(b.volume.dims).toEqual([128, 128, 128]);
    expect(b.store.level).toBe(1);
    expect(b.store.chunks).toBeGreaterThan(0);
    expect(b.store.chunks).toBeLessThanOrEqual(64);
    expect(cli('extract', store, '--level', '7', '--iso', '1').stderr).toMatch(/--level 7 does not exist \(levels 0 to \d\)/);
    truncateSync(join(store, '1/c/0/0/0'), 1000); // the level-1 shard: its index is gone
    const bad = cli('extract', store, '--level', '1', '--iso', '50');
    expect(bad.status).not.toBe(0);
    expect(bad.stderr).toMatch(/bonsai.zarr level 1 chunk \(\d, \d, \d\)/);
  });
});
