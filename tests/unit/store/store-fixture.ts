// A store converted by the converter (scripts/convert.mjs) and, as the
// in-core reference, the same volume compressed as ONE zfp stream by zfpy at
// the same rate (write_header=True): the converter README says why the blocks
// are identical. Chunk ranges come from the store's ranges/0 array (zarr).
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import type { ChunkLevelLayout } from '../../../src/store/types.ts';
import { repoRoot, sharedData } from '../../helpers/python.ts';

export interface StoreFixture {
  layout: ChunkLevelLayout;
  /** Bytes of chunk index i (as stored). */
  chunk(i: number): Uint8Array;
  /** [min, max] per chunk (ranges/0), chunk index order. */
  ranges: Float32Array;
  /** The whole level 0 as one zfp stream with header (zfpy). */
  wholeStream: Uint8Array;
  dispose(): void;
}

export function makeStore(volume: string, dtype: string, dims: [number, number, number], chunkEdge: number, rate: number): StoreFixture {
  const work = mkdtempSync(join(tmpdir(), 'zfpiso-store-'));
  const store = join(work, 's.zarr');
  execFileSync(process.execPath, [join(repoRoot, 'scripts/convert.mjs'), join(sharedData, 'volumes', volume), '--out', store, '--chunk', String(chunkEdge), '--rate', String(rate), '--quiet'], {
    cwd: repoRoot,
    stdio: 'pipe',
    timeout: 900_000,
  });
  const python = join(repoRoot, '.venv-converter/bin/python');
  execFileSync(python, ['-c', `
import sys, numpy as np, zfpy, zarr
src, store, out, dtype, x, y, z, rate = sys.argv[1:9]
a = np.fromfile(src, dtype=dtype).reshape(int(z), int(y), int(x)).astype(np.float32)
open(out + '/whole.zfp', 'wb').write(zfpy.compress_numpy(a, rate=float(rate), write_header=True))
r = zarr.open_group(store, mode='r')['ranges/0'][:]
np.ascontiguousarray(r, dtype='<f4').tofile(out + '/ranges.f32')
`, join(sharedData, 'volumes', volume), store, work, dtype, ...dims.map(String), String(rate)], { encoding: 'utf8', timeout: 300_000 });
  const chunkGrid = dims.map((n) => Math.ceil(n / chunkEdge)) as [number, number, number];
  const [gx, gy] = chunkGrid;
  const chunk = (i: number) => {
    const x = i % gx;
    const y = Math.floor(i / gx) % gy;
    const z = Math.floor(i / (gx * gy));
    return new Uint8Array(readFileSync(join(store, '0', 'c', String(z), String(y), String(x))));
  };
  const chunkBytes = chunk(0).byteLength;
  return {
    layout: { dims, chunkEdge, chunkGrid, rate, chunkBytes, name: `${volume} store level 0` },
    chunk,
    ranges: (() => {
      const b = readFileSync(join(work, 'ranges.f32'));
      return new Float32Array(b.buffer.slice(b.byteOffset, b.byteOffset + b.byteLength));
    })(),
    wholeStream: new Uint8Array(readFileSync(join(work, 'whole.zfp'))),
    dispose: () => rmSync(work, { recursive: true, force: true }),
  };
}

/** Chunks whose range united with their 26 neighbours' contains iso (what the store side fetches). */
export function neededChunks(f: StoreFixture, iso: number): number[] {
  const [gx, gy, gz] = f.layout.chunkGrid;
  const out: number[] = [];
  for (let z = 0; z < gz; z++)
    for (let y = 0; y < gy; y++)
      for (let x = 0; x < gx; x++) {
        let lo = Infinity;
        let hi = -Infinity;
        for (let k = Math.max(0, z - 1); k <= Math.min(gz - 1, z + 1); k++)
          for (let j = Math.max(0, y - 1); j <= Math.min(gy - 1, y + 1); j++)
            for (let i = Math.max(0, x - 1); i <= Math.min(gx - 1, x + 1); i++) {
              const c = i + gx * (j + gy * k);
              lo = Math.min(lo, f.ranges[2 * c]);
              hi = Math.max(hi, f.ranges[2 * c + 1]);
            }
        if (lo <= iso && iso <= hi) out.push(x + gx * (y + gy * z));
      }
  return out;
}

/** Vertices (packed pairs) as a sorted list of strings, to compare soups as multisets. */
export function sortedSoup(v: Uint32Array): string[] {
  const out: string[] = [];
  for (let i = 0; i < v.length; i += 2) out.push(`${v[i + 1]}:${v[i]}`);
  return out.sort();
}
