// Per-brick value ranges of a store of lossless chunks, written apart from it
// (`npm run convert -- --ranges-only STORE --out RANGES.zarr`,
// converter/zfpzarr/ranges_only.py): a Zarr v3 group with `ranges/<L>`
// float32 [gz, gy, gx, 2] over the page's bricks, for one rate, time point
// and channel (attributes `zfpzarr_ranges`). They let the plan skip bricks
// before fetching them, as a converted store's range arrays do.
import type { AbsolutePath, AsyncReadable, GetOptions } from '@zarrita/storage';
import * as zarr from 'zarrita';
import { describeTransportError, RequestFailedError, StoreError } from './errors.ts';
import { isObject, type Json, MetadataMemo } from './metadata.ts';
import { type RetryPolicy, RetryingStore } from './retrying-store.ts';
import { MeteredStore, type StoreMeter } from './stores.ts';

export interface SidecarLevel {
  path: string;
  brick: number;
  /** Bricks per axis, x, y, z. */
  grid: [number, number, number];
}

export interface RangesSidecar {
  name: string;
  rate: number;
  time: number;
  channel: number;
  levels: SidecarLevel[];
  /** [min, max] per brick of level L (brick index order, x fastest). */
  read(level: number, options?: GetOptions): Promise<Float32Array>;
}

export async function openRangesSidecar(
  store: AsyncReadable,
  name: string,
  meter: StoreMeter,
  retry?: RetryPolicy,
): Promise<RangesSidecar> {
  const mem = new MetadataMemo(new RetryingStore(new MeteredStore(store, meter), retry));
  let root: Json | null;
  try {
    root = await mem.jsonOrNull('/zarr.json');
  } catch (e) {
    if (e instanceof StoreError && e.kind === 'corrupt') throw new StoreError('corrupt', `${name}: ${e.message}`);
    throw describeTransportError(e, name);
  }
  const info = (isObject(root?.attributes) ? (root.attributes as Json).zfpzarr_ranges : null) as Json | null;
  if (!root || !isObject(info) || !Array.isArray(info.levels))
    throw new StoreError(
      'not-a-store',
      `${name}: not a ranges sidecar (no zarr.json with zfpzarr_ranges attributes); write one with npm run convert -- --ranges-only STORE --out RANGES.zarr`,
    );
  const levels = (info.levels as Json[]).map((l) => {
    const grid = l.grid as number[];
    if (!Array.isArray(grid) || grid.length !== 3 || !grid.every((g) => Number.isInteger(g) && g >= 1 && g <= 2 ** 24))
      throw new StoreError('corrupt', `${name}: a level's brick grid ${JSON.stringify(l.grid)} is not three counts`);
    return { path: String(l.path), brick: Number(l.brick), grid: [grid[0], grid[1], grid[2]] as [number, number, number] };
  });
  const rate = Number(info.rate);
  return {
    name,
    rate,
    time: Number(info.time ?? 0),
    channel: Number(info.channel ?? 0),
    levels,
    async read(level, opts) {
      const L = levels[level];
      const where = `${name} ranges/${level}`;
      try {
        const arr = await zarr.open.v3(zarr.root(mem).resolve(`ranges/${level}` as AbsolutePath), { kind: 'array' });
        const [gx, gy, gz] = L.grid;
        const s = arr.shape;
        if (arr.dtype !== 'float32' || s.length !== 4 || s[0] !== gz || s[1] !== gy || s[2] !== gx || s[3] !== 2)
          throw new StoreError('corrupt', `${where}: ${arr.dtype} [${s.join(', ')}], expected float32 [${gz}, ${gy}, ${gx}, 2]`);
        const got = await zarr.get(arr, null, { opts });
        return new Float32Array(got.data as Float32Array);
      } catch (e) {
        if (e instanceof StoreError && !(e instanceof RequestFailedError)) throw e;
        if (zarr.isZarritaError(e)) throw new StoreError('corrupt', `${where}: ${(e as Error).message}`, { cause: e });
        throw describeTransportError(e, where);
      }
    },
  };
}
