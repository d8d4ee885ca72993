// Opens a converter-made (or any zfpy fixed-rate) Zarr v3 store through
// zarrita: the group's attributes ("ome" multiscales, our "zfpzarr"), each
// level's array metadata, per-chunk ranges (ranges/<L>, when present), and
// chunk bytes as stored (zfpy-passthrough.ts). Everything a level needs is
// checked before any chunk is fetched; each chunk is checked as it arrives
// (size and zfp header), so the GPU only ever sees well-formed streams.
import type { AbsolutePath, AsyncReadable } from '@zarrita/storage';
import * as zarr from 'zarrita';
import { constantChunkStream } from '../../zfp/cpu/constant-stream.ts';
import { bitsPerBlockForRate } from '../../zfp/format.ts';
import { surfaceDimsProblem } from '../../core/limits.ts';
import { parseZfpHeader } from '../../zfp/header.ts';
import type { ChunkIndex, ChunkLevelLayout } from '../types.ts';
export { chunkCoords, zfpChunkBytes } from './metadata.ts';
import { describeTransportError, RequestFailedError, StoreError } from './errors.ts';
import { RetryingStore } from './retrying-store.ts';
import {
  chunkCoords,
  isObject,
  type Json,
  levelPaths,
  MetadataMemo,
  multiscaleOf,
  omeTimeAxisOf,
  pyramidChain,
  voxelSizeOf,
  levelOffsetsOf,
  zfpChunkBytes,
} from './metadata.ts';
export { MetadataMemo } from './metadata.ts';
import { openSourceStore } from './open-source.ts';
import type { OpenStoreOptions, StoreLevel, ZfpStore } from './store.ts';
export type { OpenStoreOptions, StoreLevel, ZfpStore } from './store.ts';
import { MeteredStore } from './stores.ts';
import { registerZfpyPassThrough, ZFPY_CODEC, ZFPY_FIXED_RATE_MODE } from './zfpy-passthrough.ts';

/** Sane limits for sizes read from a store (hostile metadata must not allocate). */
const MAX_EDGE = 2 ** 31;
const MAX_CHUNK_EDGE = 1024;
/** 2^26 chunks: 64^3 chunks of a 2^44-voxel (64 TiB float32) level; the range array is then 512 MiB. */
const MAX_CHUNKS = 2 ** 26;
const CONVERT_HINT = 'convert it with `npm run convert -- STORE --out new.zarr` (numcodecs.zfpy fixed rate)';

function codecOf(name: string, meta: Json): { rate: number; shardChunks: number } {
  const codecs = meta.codecs as Json[] | undefined;
  if (!Array.isArray(codecs) || codecs.length === 0)
    throw new StoreError('codec', `${name}: no codecs (raw float32 chunks); ${CONVERT_HINT}`);
  let list = codecs;
  let shardChunks = 1;
  if (list.length === 1 && list[0]?.name === 'sharding_indexed') {
    const cfg = list[0].configuration as Json;
    list = (cfg?.codecs as Json[]) ?? [];
    const outer = ((meta.chunk_grid as Json)?.configuration as Json)?.chunk_shape as number[];
    const inner = cfg?.chunk_shape as number[];
    shardChunks = Math.round(outer[outer.length - 1] / inner[inner.length - 1]);
  }
  const names = list.map((c) => String(c?.name));
  if (list.length !== 1 || names[0] !== ZFPY_CODEC) {
    throw new StoreError(
      'codec',
      `${name}: its chunks are encoded with ${names.join(' + ') || 'nothing'}, not numcodecs.zfpy fixed rate; ${CONVERT_HINT}`,
    );
  }
  const cfg = (list[0].configuration ?? {}) as Json;
  if (cfg.mode !== ZFPY_FIXED_RATE_MODE) {
    const kind = { 3: 'fixed precision', 4: 'fixed accuracy', 5: 'reversible' }[Number(cfg.mode)] ?? `mode ${String(cfg.mode)}`;
    throw new StoreError(
      'codec',
      `${name}: numcodecs.zfpy in ${kind} mode; only fixed rate (mode 2) gives chunks of one size that the GPU decodes; ${CONVERT_HINT}`,
    );
  }
  const rate = Number(cfg.rate);
  if (!(rate >= 0.140625 && rate <= 32)) throw new StoreError('codec', `${name}: zfpy rate ${String(cfg.rate)} is outside 0.140625..32`);
  return { rate, shardChunks };
}

/** A level as opened here: with the length of its t axis (1 without one). */
type ZfpLevel = StoreLevel & { timeCount: number };

async function openLevel(
  mem: MetadataMemo,
  storeName: string,
  index: number,
  path: string,
  rangesPath: string | null,
  omeAxes: string[] | null,
  time: number | undefined,
): Promise<ZfpLevel> {
  const name = `${storeName} level ${index}${path === String(index) || path === '' ? '' : ` (${path})`}`;
  const key = (path ? `/${path}/zarr.json` : '/zarr.json') as AbsolutePath;
  let meta: Json;
  try {
    meta = await mem.json(key);
  } catch (e) {
    if (e instanceof StoreError && e.kind === 'not-found') throw new StoreError('not-found', `${name}: its zarr.json is missing`);
    if (e instanceof StoreError && e.kind === 'corrupt') throw new StoreError('corrupt', `${name}: ${e.message}`);
    throw describeTransportError(e, name);
  }
  if (meta.node_type !== 'array') throw new StoreError('not-a-store', `${name}: not an array`);
  if (meta.data_type !== 'float32')
    throw new StoreError('codec', `${name}: values are ${String(meta.data_type)}, the GPU decoder reads float32 zfp; ${CONVERT_HINT}`);
  const { rate, shardChunks } = codecOf(name, meta);
  const arr = await zarr.open.v3(zarr.root(mem).resolve(path || '/'), { kind: 'array' });
  const shape = arr.shape;
  const chunks = arr.chunks;
  // axes before z, y, x: t (any length: the time point asked for) or of length 1, each in chunks of 1 (a chunk is one 3-D stream)
  const lead = shape.length - 3;
  if (lead < 0) throw new StoreError('layout', `${name}: shape [${shape.join(', ')}] is not a 3D volume`);
  const dimNames = Array.isArray(meta.dimension_names) ? (meta.dimension_names as unknown[]).map(String) : null;
  const axisNames = omeAxes?.length === shape.length ? omeAxes : dimNames?.length === shape.length ? dimNames : null;
  const leadingIndex: number[] = [];
  let timeCount = 1;
  for (let i = 0; i < lead; i++) {
    const isTime = axisNames?.[i] === 't' || axisNames?.[i] === 'time';
    if (!isTime && shape[i] !== 1) throw new StoreError('layout', `${name}: shape [${shape.join(', ')}] is not a 3D volume`);
    if (chunks[i] !== 1)
      throw new StoreError(
        'layout',
        `${name}: chunks [${chunks.join(', ')}] hold ${chunks[i]} ${isTime ? 'time points' : 'planes of a leading axis'}; a zfp chunk here is one 3-D volume (chunks of 1 along ${axisNames?.[i] ?? `axis ${i}`}); ${CONVERT_HINT}`,
      );
    const index = isTime ? (time ?? 0) : 0;
    if (!Number.isInteger(index) || index < 0 || index >= shape[i])
      throw new StoreError('layout', `${name}: time point ${index} is outside 0..${shape[i] - 1}`);
    if (isTime) timeCount = shape[i];
    leadingIndex.push(index);
  }
  const [z, y, x] = shape.slice(lead);
  const [cz, cy, cx] = chunks.slice(lead);
  if (cz !== cy || cy !== cx) throw new StoreError('layout', `${name}: chunks [${chunks.join(', ')}] are not cubes; ${CONVERT_HINT}`);
  if (cx % 4 !== 0 || cx <= 0)
    throw new StoreError(
      'layout',
      `${name}: chunk edge ${cx} is not a multiple of 4 (zfp's 4^3 blocks would straddle chunks); ${CONVERT_HINT} --chunk 64`,
    );
  if (![x, y, z].every((n) => Number.isInteger(n) && n >= 1 && n <= MAX_EDGE))
    throw new StoreError(
      'layout',
      `${name}: shape [${shape.join(', ')}] is not a volume this reader takes (1 to ${MAX_EDGE} voxels per axis)`,
    );
  if (cx > MAX_CHUNK_EDGE)
    throw new StoreError('layout', `${name}: chunk edge ${cx} is above ${MAX_CHUNK_EDGE}; ${CONVERT_HINT} --chunk 64`);
  const C = cx;
  const chunkGrid: [number, number, number] = [Math.ceil(x / C), Math.ceil(y / C), Math.ceil(z / C)];
  const chunkCount = chunkGrid[0] * chunkGrid[1] * chunkGrid[2];
  if (chunkCount > MAX_CHUNKS)
    throw new StoreError(
      'layout',
      `${name}: ${chunkGrid.join(' x ')} chunks of ${C}^3; this reader takes at most ${MAX_CHUNKS} per level (convert with a larger --chunk)`,
    );
  const chunkBytes = zfpChunkBytes(C, rate);
  const tooWide = surfaceDimsProblem([x, y, z]);
  const unusable = tooWide ? `${name}: ${tooWide}` : null;
  return {
    unusable,
    index,
    path,
    shardChunks,
    chunkCount,
    storedBytes: chunkCount * chunkBytes,
    rangesPath,
    leadingAxes: lead,
    leadingIndex,
    timeCount,
    layout: { dims: [x, y, z], chunkEdge: C, chunkGrid, rate, chunkBytes, name },
  };
}

/** Checks a chunk's stored bytes against its level: size, zfp header, dims, fixed rate. */
export function checkChunk(layout: ChunkLevelLayout, chunk: ChunkIndex, bytes: Uint8Array): void {
  const [x, y, z] = chunkCoords(layout, chunk);
  const where = `${layout.name} chunk (${x}, ${y}, ${z})`;
  if (bytes.length !== layout.chunkBytes) {
    throw new StoreError(
      'corrupt',
      `${where}: ${bytes.length} bytes, a zfp fixed-rate ${layout.chunkEdge}^3 chunk at rate ${layout.rate} has ${layout.chunkBytes}`,
    );
  }
  let header;
  try {
    header = parseZfpHeader(bytes);
  } catch (e) {
    throw new StoreError('corrupt', `${where}: not a zfp stream (${(e as Error).message})`);
  }
  const C = layout.chunkEdge;
  const [nx, ny, nz] = header.size;
  if (header.scalarType !== 'float32' || header.dimensionality !== 3 || nx !== C || ny !== C || nz !== C) {
    throw new StoreError(
      'corrupt',
      `${where}: its zfp header says ${header.scalarType} ${header.size.slice(0, header.dimensionality).join('x')}, the level has float32 ${C}^3 chunks`,
    );
  }
  if (header.mode.kind !== 'fixed-rate' || header.mode.maxBits !== bitsPerBlockForRate(layout.rate)) {
    throw new StoreError(
      'corrupt',
      `${where}: its zfp header says ${header.mode.kind} with ${header.mode.maxBits} bits per block, the level is fixed rate ${layout.rate}`,
    );
  }
}

/**
 * Opens the store; `name` is for messages (its URL or folder). A Zarr v3
 * store whose chunks are numcodecs.zfpy fixed-rate streams goes to the GPU
 * as stored; any other Zarr v2 or v3 array or OME-Zarr multiscale group is
 * read as a store of lossless chunks (source-store.ts), compressed on the
 * GPU as bricks arrive. Rejects with StoreError.
 */
export async function openStore(store: AsyncReadable, name: string, options: OpenStoreOptions = {}): Promise<ZfpStore> {
  registerZfpyPassThrough();
  const metered = store instanceof MeteredStore ? store : new MeteredStore(store);
  const retrying = new RetryingStore(metered, options.retry);
  const mem = new MetadataMemo(retrying);
  const named = async (key: AbsolutePath) => {
    try {
      return await mem.jsonOrNull(key);
    } catch (e) {
      if (e instanceof StoreError && e.kind === 'corrupt') throw new StoreError('corrupt', `${name}: ${e.message}`);
      throw describeTransportError(e, name);
    }
  };
  const rootJson = await named('/zarr.json');
  if (!rootJson) {
    const zarray = await named('/.zarray');
    const zgroup = zarray ? null : await named('/.zgroup');
    if (!zarray && !zgroup)
      throw new StoreError(
        'not-found',
        `${name}: no zarr.json, .zgroup or .zarray at its root (HTTP 404 or no such folder): not a Zarr store`,
      );
    const attrs = (await named('/.zattrs')) ?? {};
    return openSourceStore({ mem, metered, retrying }, name, 2, zarray ? 'array' : 'group', attrs, options);
  }
  if (rootJson.zarr_format !== 3)
    throw new StoreError('not-a-store', `${name}: its zarr.json says zarr_format ${String(rootJson.zarr_format)}, not 3`);
  const attrs = (isObject(rootJson.attributes) ? rootJson.attributes : {}) as Json;
  const kind = rootJson.node_type === 'array' ? 'array' : 'group';
  const firstPath = kind === 'array' ? '' : levelPaths(attrs)?.[0];
  if (firstPath === undefined) throw new StoreError('not-a-store', `${name}: a Zarr group without OME-Zarr multiscales or zfpzarr levels`);
  const first = kind === 'array' ? rootJson : await named(`/${firstPath}/zarr.json` as AbsolutePath);
  if (first && !isZfpArray(first)) return openSourceStore({ mem, metered, retrying }, name, 3, kind, attrs, options);
  return openZfpLevels({ mem, metered, retrying }, name, rootJson, options.time);
}

/** Whether a v3 array's chunks are numcodecs.zfpy streams (inside shards or not). */
function isZfpArray(meta: Json): boolean {
  const codecs = (Array.isArray(meta.codecs) ? meta.codecs : []) as Json[];
  return codecs.some(
    (c) =>
      c?.name === ZFPY_CODEC ||
      (c?.name === 'sharding_indexed' && ((c.configuration as Json)?.codecs as Json[] | undefined)?.some((i) => i?.name === ZFPY_CODEC)),
  );
}

interface StoreLayers {
  mem: MetadataMemo;
  metered: MeteredStore;
  retrying: RetryingStore;
}

async function openZfpLevels(
  { mem, metered, retrying }: StoreLayers,
  name: string,
  rootJson: Json,
  time: number | undefined,
): Promise<ZfpStore> {
  const levels: ZfpLevel[] = [];
  const notes: string[] = [];
  let attrs: Json = {};
  let chain: number[] | undefined;
  let scales: [number, number, number][] | undefined;
  if (rootJson.node_type === 'array') {
    levels.push(await openLevel(mem, name, 0, '', null, null, time));
  } else {
    const group = await zarr.open.v3(zarr.root(mem), { kind: 'group' });
    attrs = (group.attrs ?? {}) as Json;
    const paths = levelPaths(attrs);
    if (!paths) throw new StoreError('not-a-store', `${name}: a Zarr group without OME-Zarr multiscales or zfpzarr levels`);
    const ours = isObject(attrs.zfpzarr) ? attrs.zfpzarr : null;
    const ourLevels = (ours?.levels as Json[] | undefined) ?? [];
    if (ours && ours.complete !== true) notes.push('the store is unfinished (zfpzarr.complete is not true): chunks may be missing');
    // levels that span powers of two of level 0's voxels, coarser each time; other datasets are left out (and said so)
    const pyramid = pyramidChain(attrs, paths.length);
    chain = pyramid.datasets;
    scales = pyramid.scales;
    if (pyramid.skipped) notes.push(pyramid.skipped);
    for (const [i, d] of chain.entries()) {
      const rp = ourLevels.find((l) => String(l.path) === paths[d])?.ranges;
      levels.push(await openLevel(mem, name, i, paths[d], typeof rp === 'string' ? rp : null, omeAxesOf(attrs), time));
    }
  }
  const unusable = levels.filter((l) => l.unusable);
  if (unusable.length === levels.length) throw new StoreError('layout', unusable[0].unusable!);
  if (unusable.length > 0)
    notes.push(
      `levels ${unusable.map((l) => l.index).join(', ')} cannot be shown (${unusable[0].unusable}); the finest shown is level ${unusable.at(-1)!.index + 1}`,
    );
  if (levels.some((l) => !l.rangesPath))
    notes.push(
      'no per-chunk range arrays: the first surface of a level fetches every chunk of it (ranges are computed on the GPU as chunks arrive)',
    );
  // A chunk absent from the store holds the array's fill value (Zarr): its stream is made once per level.
  const fillChunks = new Map<number, Uint8Array>();
  const fillChunk = (level: number, fill: unknown, where: string): Uint8Array => {
    let bytes = fillChunks.get(level);
    if (!bytes) {
      const value = fill === null || fill === undefined ? 0 : Number(fill);
      if (!Number.isFinite(value))
        throw new StoreError(
          'missing-chunk',
          `${where}: the chunk is absent, and the array's fill value ${String(fill)} is not a number zfp can hold`,
        );
      const L = levels[level].layout;
      bytes = constantChunkStream(L.chunkEdge, L.rate, value);
      fillChunks.set(level, bytes);
    }
    return bytes;
  };
  const arrays = new Map<number, Promise<zarr.Array<zarr.DataType, MetadataMemo>>>();
  const arrayOf = (level: number) => {
    let a = arrays.get(level);
    if (!a) {
      a = zarr.open.v3(zarr.root(mem).resolve(levels[level].path || '/'), { kind: 'array' });
      a.catch(() => arrays.delete(level)); // a failed open is tried again by the next chunk
      arrays.set(level, a);
    }
    return a;
  };
  const ours = isObject(attrs.zfpzarr) ? attrs.zfpzarr : null;
  const timeCount = levels[0].timeCount;
  const timeIndex = levels[0].leadingIndex?.[omeTimeAxisOf(attrs)?.axis ?? -1] ?? time ?? 0;
  if (levels.some((l) => l.timeCount !== timeCount))
    throw new StoreError(
      'layout',
      `${name}: its levels have ${levels.map((l) => l.timeCount).join(', ')} time points; each level holds every time point`,
    );
  // a series: the decoded range of the time point shown (the converter's value_ranges), else the store's
  const perTime = ours?.value_ranges as unknown[] | undefined;
  const vr = (Array.isArray(perTime) && perTime.length === timeCount ? perTime[timeIndex] : ours?.value_range) as number[] | undefined;
  const omeTime = omeTimeAxisOf(attrs);
  return {
    name,
    levels,
    notes,
    source: null,
    meter: metered.meter,
    retries: retrying.counters,
    metadataBytes: metered.meter.bytes,
    voxelSize: voxelSizeOf(attrs),
    levelOffsets: levelOffsetsOf(attrs, levels.length, chain),
    levelScales: levels.map((_, L) => scales?.[L] ?? [2 ** L, 2 ** L, 2 ** L]),
    unit: typeof ours?.unit === 'string' ? ours.unit : null,
    ...(levels[0].leadingAxes > 0 && (omeTime || timeCount > 1)
      ? {
          time: {
            index: timeIndex,
            count: timeCount,
            step: omeTime?.scale ?? null,
            origin: omeTime?.origin ?? 0,
            unit: omeTime?.unit ?? null,
          },
        }
      : {}),
    valueRange: Array.isArray(vr) && vr.length === 2 ? [Number(vr[0]), Number(vr[1])] : null,
    isAbsent(bytes) {
      for (const fill of fillChunks.values()) if (fill === bytes) return true;
      return false;
    },
    async readChunk(level, chunk, opts) {
      const L = levels[level];
      const [x, y, z] = chunkCoords(L.layout, chunk);
      const where = `${L.layout.name} chunk (${x}, ${y}, ${z})`;
      let got;
      let arr;
      try {
        arr = await arrayOf(level);
        got = await arr.getChunk([...(L.leadingIndex ?? new Array<number>(L.leadingAxes).fill(0)), z, y, x], opts);
      } catch (e) {
        if (zarr.isZarritaError(e, 'CodecPipelineError'))
          throw new StoreError('corrupt', `${where}: ${e.message} (a damaged shard index?)`, { cause: e });
        throw describeTransportError(e, where);
      }
      // absent (HTTP 404, no file): the fill value, as Zarr defines it
      if (!(got.data instanceof Uint8Array)) return fillChunk(level, arr.fillValue, where);
      checkChunk(L.layout, chunk, got.data);
      return got.data;
    },
    async readRanges(level, opts) {
      const L = levels[level];
      if (!L.rangesPath) return null;
      try {
        const arr = await zarr.open.v3(zarr.root(mem).resolve(L.rangesPath), { kind: 'array' });
        const [gx, gy, gz] = L.layout.chunkGrid;
        // a series: [t, cz, cy, cx, 2], the ranges of each time point
        const s = arr.shape;
        const series = L.timeCount > 1 || s.length === 5;
        const want = [...(series ? [L.timeCount] : []), gz, gy, gx, 2];
        if (arr.dtype !== 'float32' || s.length !== want.length || s.some((n, i) => n !== want[i])) {
          throw new StoreError(
            'corrupt',
            `${L.layout.name}: its range array ${L.rangesPath} is ${arr.dtype} [${s.join(', ')}], expected float32 [${want.join(', ')}]`,
          );
        }
        const got = await zarr.get(arr, series ? [timeIndex, null, null, null, null] : null, { opts });
        return new Float32Array(got.data as Float32Array);
      } catch (e) {
        if (e instanceof StoreError && !(e instanceof RequestFailedError)) throw e;
        if (zarr.isZarritaError(e))
          throw new StoreError('corrupt', `${L.layout.name}: its range array ${L.rangesPath}: ${(e as Error).message}`, { cause: e });
        throw describeTransportError(e, `${L.layout.name} ranges`);
      }
    },
  };
}

/** The OME axes' names of the first multiscale, or null. */
function omeAxesOf(attrs: Json): string[] | null {
  const ms = multiscaleOf(attrs);
  const axes = ms && Array.isArray(ms.axes) ? (ms.axes as Array<Json | string>) : null;
  return axes ? axes.map((a) => (typeof a === 'string' ? a : String(a?.name))) : null;
}
