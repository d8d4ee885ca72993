// What the store readers share: JSON helpers, OME-Zarr multiscales (level
// paths, voxel size), and the sizes of zfp chunks.
import { bitsPerBlockForRate, fixedRateStreamBytes } from '../../zfp/format.ts';
import { ZFP_LONG_HEADER_BITS, ZFP_SHORT_HEADER_BITS } from '../../zfp/header.ts';
import type { AbsolutePath, AsyncReadable, GetOptions } from '@zarrita/storage';
import type { ChunkIndex, ChunkLevelLayout } from '../types.ts';
import { StoreError } from './errors.ts';
import type { RetryingStore } from './retrying-store.ts';

export type Json = Record<string, unknown>;
export const isObject = (v: unknown): v is Json => typeof v === 'object' && v !== null && !Array.isArray(v);

export function chunkCoords(layout: ChunkLevelLayout, chunk: ChunkIndex): [number, number, number] {
  const [gx, gy] = layout.chunkGrid;
  return [chunk % gx, Math.floor(chunk / gx) % gy, Math.floor(chunk / (gx * gy))];
}

/** Bytes of one C^3 chunk as zfpy writes it at this rate (header + blocks, padded to 64 bits). */
export function zfpChunkBytes(chunkEdge: number, rate: number): number {
  const bits = bitsPerBlockForRate(rate);
  const headerBits = bits > 2048 ? ZFP_LONG_HEADER_BITS : ZFP_SHORT_HEADER_BITS;
  return fixedRateStreamBytes((chunkEdge / 4) ** 3, bits, headerBits);
}

/** The OME multiscale (0.4: in the attributes; 0.5: under "ome"), or null. */
export function multiscaleOf(attrs: Json): Json | null {
  const ome = (isObject(attrs.ome) ? attrs.ome : attrs) as Json;
  const ms = ome.multiscales as Json[] | undefined;
  return Array.isArray(ms) && isObject(ms[0]) ? ms[0] : null;
}

export function levelPaths(attrs: Json): string[] | null {
  const ome = (isObject(attrs.ome) ? attrs.ome : attrs) as Json;
  const ms = ome.multiscales as Json[] | undefined;
  const datasets = Array.isArray(ms) && isObject(ms[0]) ? (ms[0].datasets as Json[]) : undefined;
  if (Array.isArray(datasets) && datasets.length > 0) return datasets.map((d) => String(d.path));
  const ours = attrs.zfpzarr as Json | undefined;
  if (isObject(ours) && Array.isArray(ours.levels)) return (ours.levels as Json[]).map((l) => String(l.path));
  return null;
}

export function voxelSizeOf(attrs: Json): [number, number, number] {
  const ours = attrs.zfpzarr as Json | undefined;
  const v = isObject(ours) ? (ours.voxel_size as number[] | undefined) : undefined;
  if (Array.isArray(v) && v.length === 3 && v.every((x) => Number.isFinite(x) && x > 0)) return [v[0], v[1], v[2]];
  const ms = ((isObject(attrs.ome) ? attrs.ome : attrs) as Json).multiscales as Json[] | undefined;
  const t = Array.isArray(ms) ? (((ms[0]?.datasets as Json[])?.[0]?.coordinateTransformations as Json[]) ?? []) : [];
  const scale = t.find((x) => x.type === 'scale')?.scale as number[] | undefined;
  if (Array.isArray(scale) && scale.length >= 3) {
    const [z, y, x] = scale.slice(-3);
    if ([x, y, z].every((s) => Number.isFinite(s) && s > 0)) return [x, y, z];
  }
  return [1, 1, 1];
}

/**
 * The datasets that make a pyramid the viewer can draw, and each one's
 * scale: how many level-0 voxels one of its voxels spans on x, y and z.
 * Level 0, then each dataset whose OME `scale` is a power of two times level
 * 0's on every axis, at least the previous level's on every axis and more on
 * one (ngff-zarr's per-axis scale factors: a 128x128x256 volume's level 1 at
 * 128x128x128 spans (1, 1, 2)); the others (not a power of two, finer than
 * the level before) are left out and named in `skipped`. Without scales on
 * every dataset, all of them, level L spanning 2^L on every axis (the
 * converter's and zarr-python's stores).
 */
export function pyramidChain(
  attrs: Json,
  count: number,
): { datasets: number[]; scales: [number, number, number][]; skipped: string | null } {
  const ms = multiscaleOf(attrs);
  const list = ms && Array.isArray(ms.datasets) ? (ms.datasets as Json[]) : [];
  const scales = list.slice(0, count).map((d) => {
    const t = Array.isArray(d.coordinateTransformations) ? (d.coordinateTransformations as Json[]) : [];
    const v = t.find((x) => isObject(x) && x.type === 'scale')?.scale as number[] | undefined;
    if (!Array.isArray(v) || v.length < 3) return null;
    const [z, y, x] = v.slice(-3).map(Number);
    return [x, y, z].every((a) => Number.isFinite(a) && a > 0) ? [x, y, z] : null;
  });
  const all = Array.from({ length: count }, (_, i) => i);
  if (scales.length < count || scales.some((sc) => sc === null))
    return { datasets: all, scales: all.map((L) => [2 ** L, 2 ** L, 2 ** L]), skipped: null };
  const s0 = scales[0]!;
  const datasets: number[] = [0];
  const chainScales: [number, number, number][] = [[1, 1, 1]];
  const left: string[] = [];
  for (let i = 1; i < count; i++) {
    const f = scales[i]!.map((v, a) => v / s0[a]);
    const pow2 = f.map((v) => 2 ** Math.round(Math.log2(v)));
    const prev = chainScales[chainScales.length - 1];
    const exact = f.every((v, a) => Math.abs(v - pow2[a]) <= 1e-6 * pow2[a]);
    if (exact && pow2.every((v, a) => v >= prev[a]) && pow2.some((v, a) => v > prev[a])) {
      datasets.push(i);
      chainScales.push([pow2[0], pow2[1], pow2[2]]);
    } else left.push(`${String(list[i].path)} (${f.map((v) => Number(v.toPrecision(4))).join(' x ')} times level 0's voxel)`);
  }
  return {
    datasets,
    scales: chainScales,
    skipped:
      left.length === 0
        ? null
        : `datasets ${left.join(', ')} are not shown: each level drawn spans a power of two of level 0's voxels on every axis, and more than the level before`,
  };
}

/**
 * Where each level sits, in level-0 voxels (x, y, z): level L's voxel j at
 * level-0 index j * scale_L + offset (pyramidChain's scales). From the OME `translation` of each dataset
 * (relative to level 0's, divided by level 0's `scale`): a coarse voxel of a
 * mean pyramid is the mean of scale_L finer ones per axis and sits at their
 * centre, (scale_L - 1) / 2 (the converter writes that); a store that gives no
 * translation places its levels at 0 (nearest-neighbour pyramids). Levels
 * beyond the datasets listed (a plain array) get 0.
 */
export function levelOffsetsOf(attrs: Json, count: number, chain?: readonly number[]): [number, number, number][] {
  const ms = multiscaleOf(attrs);
  const all = ms && Array.isArray(ms.datasets) ? (ms.datasets as Json[]) : [];
  // the levels shown (pyramidChain): level L is dataset chain[L]
  const datasets = chain ? chain.map((i) => all[i]) : all;
  const transformOf = (d: Json | undefined, type: string): [number, number, number] | null => {
    const list = d && Array.isArray(d.coordinateTransformations) ? (d.coordinateTransformations as Json[]) : [];
    const v = list.find((x) => isObject(x) && x.type === type)?.[type] as number[] | undefined;
    if (!Array.isArray(v) || v.length < 3) return null;
    const [z, y, x] = v.slice(-3).map(Number);
    return [x, y, z].every(Number.isFinite) ? [x, y, z] : null;
  };
  const scale0 = transformOf(datasets[0], 'scale') ?? [1, 1, 1];
  const t0 = transformOf(datasets[0], 'translation') ?? [0, 0, 0];
  const out: [number, number, number][] = [];
  for (let L = 0; L < count; L++) {
    const t = transformOf(datasets[L], 'translation');
    out.push(
      t && scale0.every((s) => s > 0) ? [(t[0] - t0[0]) / scale0[0], (t[1] - t0[1]) / scale0[1], (t[2] - t0[2]) / scale0[2]] : [0, 0, 0],
    );
  }
  return out;
}

/** Caches JSON documents (zarr.json, .zarray, .zattrs, .zgroup) so that zarrita and our checks read each once. */
export class MetadataMemo implements AsyncReadable {
  #memo = new Map<string, Promise<Uint8Array | undefined>>();
  constructor(readonly inner: RetryingStore) {}
  get(key: AbsolutePath, opts?: GetOptions): Promise<Uint8Array | undefined> {
    if (!/(zarr\.json|\.zarray|\.zattrs|\.zgroup)$/.test(key)) return this.inner.get(key, opts);
    let hit = this.#memo.get(key);
    if (!hit) {
      hit = this.inner.get(key, opts);
      hit.catch(() => this.#memo.delete(key));
      this.#memo.set(key, hit);
    }
    return hit;
  }
  getRange(...args: Parameters<RetryingStore['getRange']>) {
    return this.inner.getRange(...args);
  }
  async json(key: AbsolutePath): Promise<Json> {
    const got = await this.jsonOrNull(key);
    if (!got) throw new StoreError('not-found', `${key} is missing`);
    return got;
  }
  async jsonOrNull(key: AbsolutePath): Promise<Json | null> {
    const bytes = await this.get(key);
    if (!bytes) return null;
    try {
      return JSON.parse(new TextDecoder().decode(bytes)) as Json;
    } catch (e) {
      throw new StoreError('corrupt', `${key} is not JSON (${(e as Error).message})`);
    }
  }
}

/**
 * The OME time axis of the first multiscale: its position among the axes,
 * and the physical time of index 0 and per index (level 0's `translation`
 * and `scale` along it), with its unit; null when the store names no axis
 * `t` / `time` (or of type "time").
 */
export function omeTimeAxisOf(attrs: Json): { axis: number; scale: number | null; origin: number; unit: string | null } | null {
  const ms = multiscaleOf(attrs);
  const axes = ms && Array.isArray(ms.axes) ? (ms.axes as Array<Json | string>) : null;
  if (!axes) return null;
  const axis = axes.findIndex((a) =>
    typeof a === 'string' ? a === 't' || a === 'time' : a?.name === 't' || a?.name === 'time' || a?.type === 'time',
  );
  if (axis < 0) return null;
  const named = axes[axis];
  const unit = typeof named !== 'string' && typeof named?.unit === 'string' ? named.unit : null;
  const d0 = Array.isArray(ms!.datasets) && isObject((ms!.datasets as Json[])[0]) ? (ms!.datasets as Json[])[0] : undefined;
  const list = d0 && Array.isArray(d0.coordinateTransformations) ? (d0.coordinateTransformations as Json[]) : [];
  const along = (type: string): number | null => {
    const v = list.find((x) => isObject(x) && x.type === type)?.[type] as unknown[] | undefined;
    const n = Array.isArray(v) && v.length === axes.length ? Number(v[axis]) : Number.NaN;
    return Number.isFinite(n) ? n : null;
  };
  const scale = along('scale');
  return { axis, scale: scale !== null && scale > 0 ? scale : null, origin: along('translation') ?? 0, unit };
}
