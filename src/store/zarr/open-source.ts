// Opens a store of lossless chunks (Zarr v2 or v3, a plain array or an
// OME-Zarr multiscale group; source-store.ts reads its bricks) as the same
// ZfpStore the store stream reads: each level's layout is of bricks
// that arrive as float32 values and are compressed on the GPU at `rate`.
import type { AbsolutePath } from '@zarrita/storage';
import * as zarr from 'zarrita';
import { checkRate } from '../../zfp/format.ts';
import { describeTransportError, StoreError } from './errors.ts';
import {
  isObject,
  type Json,
  levelPaths,
  pyramidChain,
  multiscaleOf,
  omeTimeAxisOf,
  voxelSizeOf,
  levelOffsetsOf,
  zfpChunkBytes,
} from './metadata.ts';
import type { MetadataMemo } from './metadata.ts';
import type { OpenStoreOptions, StoreLevel, ZfpStore } from './store.ts';
import { openRangesSidecar, type RangesSidecar } from './ranges-sidecar.ts';
import { BrickWorkerPool } from '../decode/brick-pool.ts';
import { brickEdge } from './brick-edge.ts';
import { storeSpecOf } from '../decode/store-spec.ts';
import type { RetryingStore } from './retrying-store.ts';
import {
  axesOf,
  BrickReader,
  type BrickSource,
  checkSourceMeta,
  codecNames,
  DEFAULT_SOURCE_RATE,
  type SourceLevel,
  sourceBytesPerValue,
  sourceLevel,
  type RateSample,
  sampleAs,
  type SourceInfo,
  sourcePrecision,
  unusableLevel,
} from './source-store.ts';
import type { MeteredStore } from './stores.ts';

/**
 * Bricks of a level spread over it, side by side along z: what the rate is
 * chosen from. As many as 8 Mi voxels hold (64 at most, at least one): a few
 * small bricks can all fall in empty space and ask for too low a rate.
 */
async function sampleBricks(sources: SourceLevel[], level: number, cacheBytes?: number): Promise<RateSample> {
  const reader = new BrickReader(sources, cacheBytes);
  const { chunkEdge: B, chunkGrid, name } = sources[level].layout;
  const count = chunkGrid[0] * chunkGrid[1] * chunkGrid[2];
  const picks = spreadBricks(chunkGrid, Math.min(count, 64, Math.max(1, Math.floor(2 ** 23 / B ** 3))));
  const values = new Float32Array(B ** 3 * picks.length);
  const bricks = await Promise.all(picks.map((b) => reader.read(level, b)));
  bricks.forEach((b, i) => values.set(new Float32Array(b.buffer, b.byteOffset, B ** 3), i * B ** 3));
  return { ...sampleAs(values, sources[level].array.dtype), dims: [B, B, B * picks.length], name };
}

/**
 * At most `k` bricks of a grid, spread in 3-D: a lattice of m per axis (all
 * of a shorter axis), the largest m that keeps their number within k, each
 * at the middle of its share of the axis. (Evenly spaced brick indices are
 * not spread: 32 of 16^3 all lie on the face x = 0, empty space around a
 * centred specimen, and the rate chosen from them was 1.)
 */
export function spreadBricks(grid: readonly [number, number, number], k: number): number[] {
  const per = (m: number) => grid.map((g) => Math.min(g, m));
  let m = 1;
  while (m < Math.max(...grid) && per(m + 1).reduce((a, b) => a * b, 1) <= k) m++;
  const at = per(m).map((n, a) => Array.from({ length: n }, (_, j) => Math.floor(((j + 0.5) * grid[a]) / n)));
  const out: number[] = [];
  for (const z of at[2]) for (const y of at[1]) for (const x of at[0]) out.push(x + grid[0] * (y + grid[1] * z));
  return out;
}

/**
 * True when the sidecar's bricks are this store's (levels, paths, brick
 * edges and grids: else a StoreError, the user named the wrong file); a
 * reason when they are for another rate, time point or channel (then the
 * store opens without them).
 */
function sidecarFits(
  sidecar: RangesSidecar,
  levels: StoreLevel[],
  rate: number,
  info: { time: SourceInfo['time']; channel: SourceInfo['channel'] },
): true | string {
  const wrong = (what: string) => {
    throw new StoreError(
      'layout',
      `${sidecar.name}: its ranges are not of this store's bricks (${what}); write them again with --ranges-only`,
    );
  };
  if (sidecar.levels.length !== levels.length) wrong(`${sidecar.levels.length} levels, the store has ${levels.length}`);
  levels.forEach((l, i) => {
    const s = sidecar.levels[i];
    if (s.path !== l.path) wrong(`level ${i} is ${s.path}, the store's is ${l.path}`);
    if (s.brick !== l.layout.chunkEdge || s.grid.some((g, a) => g !== l.layout.chunkGrid[a]))
      wrong(
        `level ${i}: ${s.grid.join('x')} bricks of ${s.brick}^3, the page reads ${l.layout.chunkGrid.join('x')} of ${l.layout.chunkEdge}^3`,
      );
  });
  if (sidecar.rate !== rate) return `its ranges are of the values at rate ${sidecar.rate}, the bricks are compressed at rate ${rate}`;
  if (sidecar.time !== info.time.index || sidecar.channel !== info.channel.index)
    return `its ranges are of time point ${sidecar.time}, channel ${sidecar.channel}; shown: ${info.time.index}, ${info.channel.index}`;
  return true;
}

export async function openSourceStore(
  layers: { mem: MetadataMemo; metered: MeteredStore; retrying: RetryingStore },
  name: string,
  format: 2 | 3,
  kind: 'array' | 'group',
  attrs: Json,
  options: OpenStoreOptions,
): Promise<ZfpStore> {
  const { mem, metered, retrying } = layers;
  const ms = multiscaleOf(attrs);
  const allPaths = kind === 'array' ? [''] : levelPaths(attrs);
  if (!allPaths) throw new StoreError('not-a-store', `${name}: a Zarr group without OME-Zarr multiscales (no levels to show)`);
  // levels that span powers of two of level 0's voxels, coarser each time; other datasets are left out (and said so)
  const chain =
    kind === 'array'
      ? { datasets: [0], scales: [[1, 1, 1]] as [number, number, number][], skipped: null }
      : pyramidChain(attrs, allPaths.length);
  const paths = chain.datasets.map((i) => allPaths[i]);
  const sidecar = options.ranges ? await openRangesSidecar(options.ranges.store, options.ranges.name, metered.meter, options.retry) : null;
  let rate = options.rate ?? sidecar?.rate ?? DEFAULT_SOURCE_RATE;
  const rateHow: SourceInfo['rateHow'] =
    options.rate !== undefined ? 'given' : sidecar ? 'sidecar' : options.chooseRate ? 'chosen' : 'default';
  try {
    checkRate(name, rate, 'asked for');
  } catch (e) {
    throw new StoreError('codec', (e as Error).message);
  }
  const axesJson = (isObject(ms) && Array.isArray(ms.axes) ? ms.axes : null) as Array<Json | string> | null;
  const omeAxes = axesJson ? axesJson.map((a) => (typeof a === 'string' ? a : String(a?.name))) : null;
  const sources: SourceLevel[] = [];
  const levels: StoreLevel[] = [];
  let firstMeta: Json | null = null;
  let info: Pick<ZfpStore['source'] & object, 'time' | 'channel' | 'axes'> | null = null;
  for (let i = 0; i < paths.length; i++) {
    const path = paths[i];
    const where = `${name} level ${i}${path === String(i) || path === '' ? '' : ` (${path})`}`;
    const metaKey = (format === 3 ? `${path ? `/${path}` : ''}/zarr.json` : `${path ? `/${path}` : ''}/.zarray`) as AbsolutePath;
    let meta: Json | null;
    try {
      meta = await mem.jsonOrNull(metaKey);
    } catch (e) {
      if (e instanceof StoreError) throw new StoreError(e.kind, `${where}: ${e.message}`);
      throw describeTransportError(e, where);
    }
    if (!meta) throw new StoreError('not-found', `${where}: its ${format === 3 ? 'zarr.json' : '.zarray'} is missing`);
    if (format === 3 && meta.node_type !== 'array') throw new StoreError('not-a-store', `${where}: not an array`);
    checkSourceMeta(where, meta, format);
    firstMeta ??= meta;
    let array: zarr.Array<zarr.DataType, zarr.Readable>;
    try {
      const loc = zarr.root(mem).resolve(path || '/');
      array = format === 3 ? await zarr.open.v3(loc, { kind: 'array' }) : await zarr.open.v2(loc, { kind: 'array', attrs: false });
    } catch (e) {
      if (zarr.isZarritaError(e)) throw new StoreError('corrupt', `${where}: ${(e as Error).message}`, { cause: e });
      throw describeTransportError(e, where);
    }
    const axes = axesOf(where, array.shape, omeAxes, { time: options.time, channel: options.channel });
    info ??= { time: axes.time, channel: axes.channel, axes: axes.names };
    // bricks that nest in the finer level's, so that the view's cut can refine every level
    const finer = sources.at(-1);
    const finerScale = chain.scales[i - 1];
    const level = sourceLevel(path, where, array, axes, rate, zfpChunkBytes, (c) =>
      brickEdge(
        c,
        chain.scales[i] ?? [2 ** i, 2 ** i, 2 ** i],
        finer && finerScale ? { edge: finer.layout.chunkEdge, scale: finerScale } : undefined,
      ),
    );
    sources.push(level);
    const { chunkGrid } = level.layout;
    levels.push({
      index: i,
      path,
      layout: level.layout,
      shardChunks: 1,
      chunkCount: chunkGrid[0] * chunkGrid[1] * chunkGrid[2],
      // what the level's values are decoded (the stored bytes are not known before fetching them)
      storedBytes: level.layout.dims.reduce((a, b) => a * b, 1) * sourceBytesPerValue(array.dtype),
      rangesPath: null,
      leadingAxes: 0,
      unusable: unusableLevel(level),
    });
  }
  const unusable = levels.filter((l) => l.unusable);
  if (unusable.length === levels.length) throw new StoreError('layout', unusable[0].unusable!);
  let rateNote: string | null = null;
  if (rateHow === 'chosen') {
    // The finest level whose bricks are its chunks of at most 64^3 (a few chunks fetched: cheap), else the coarsest:
    // coarse levels are means, smoother than the data, and may ask for a lower rate than full resolution needs.
    const shown = levels.filter((l) => !l.unusable).map((l) => sources[l.index]);
    const from = shown.find((l) => l.layout.chunkEdge <= 64 && l.chunkXYZ.every((c) => c === l.layout.chunkEdge)) ?? shown.at(-1)!;
    const chosen = await options.chooseRate!(await sampleBricks(sources, sources.indexOf(from), options.sourceCacheBytes));
    rate = chosen.rate;
    rateNote = `${chosen.description} (${from.layout.name})`;
    for (const l of sources) {
      l.layout.rate = rate;
      l.layout.chunkBytes = zfpChunkBytes(l.layout.chunkEdge, rate);
    }
  }
  const a0 = sources[0].array;
  const codecs = codecNames(firstMeta!, format).shown;
  const cube = sources[0].layout.chunkEdge === sources[0].chunkXYZ[0] && sources[0].chunkXYZ.every((c) => c === sources[0].chunkXYZ[0]);
  const notes = [
    `lossless chunks (${codecs.join(' + ') || 'uncompressed'}, ${a0.dtype}): each ${sources[0].layout.chunkEdge}^3 brick is compressed on the GPU at rate ${rate} as it arrives`,
  ];
  if (rateNote) notes.push(rateNote);
  if (chain.skipped) notes.push(chain.skipped);
  const usable = sidecar ? sidecarFits(sidecar, levels, rate, info!) : null;
  if (sidecar && usable === true) {
    for (const l of levels) l.rangesPath = `${sidecar.name} ranges/${l.index}`;
    notes.push(`per-brick ranges from ${sidecar.name} (rate ${sidecar.rate}): a surface fetches only the bricks it needs`);
  } else {
    if (typeof usable === 'string') notes.push(`${sidecar!.name} is not used: ${usable}`);
    notes.push(
      'no per-chunk range arrays: the first surface of a level fetches all of it (ranges are computed on the GPU as bricks arrive; npm run convert -- --ranges-only STORE --out RANGES.zarr writes them, for &ranges=URL / --ranges)',
    );
  }
  if (unusable.length > 0)
    notes.push(
      `levels ${unusable.map((l) => l.index).join(', ')} cannot be shown (${unusable[0].unusable}); the finest shown is level ${unusable.at(-1)!.index + 1}`,
    );
  // off the main thread where workers exist and can open the store again (the page); here otherwise (the CLI, tests)
  const spec = options.decodeWorkers && typeof Worker !== 'undefined' ? storeSpecOf(metered) : null;
  const reader: BrickSource = spec
    ? new BrickWorkerPool(
        sources,
        spec,
        format,
        metered.meter,
        retrying.counters,
        typeof options.decodeWorkers === 'number' ? options.decodeWorkers : undefined,
        options.sourceCacheBytes,
      )
    : new BrickReader(sources, options.sourceCacheBytes);
  if (spec)
    notes.push(
      `chunks are decoded in ${(reader as BrickWorkerPool).workerCount} Web Worker${(reader as BrickWorkerPool).workerCount === 1 ? '' : 's'}`,
    );
  const axisUnit = (axis: string) => {
    const a = axesJson?.find((x) => typeof x !== 'string' && x?.name === axis) as Json | undefined;
    return typeof a?.unit === 'string' ? a.unit : null;
  };
  return {
    name,
    levels,
    notes,
    source: {
      format: format === 3 ? 'Zarr v3' : 'Zarr v2',
      codecs,
      dtype: a0.dtype,
      chunkShape: [...a0.chunks],
      axes: info!.axes,
      time: info!.time,
      channel: info!.channel,
      bricks: cube ? 'chunks' : `bricks of ${sources[0].layout.chunkEdge}^3`,
      rate,
      rateHow,
      rateNote,
      precision: sourcePrecision(a0.dtype),
    },
    meter: metered.meter,
    retries: retrying.counters,
    metadataBytes: metered.meter.bytes,
    voxelSize: voxelSizeOf(attrs),
    levelOffsets: levelOffsetsOf(attrs, levels.length, chain.datasets),
    levelScales: levels.map((_, L) => chain.scales[L] ?? [2 ** L, 2 ** L, 2 ** L]),
    unit: axisUnit('x'),
    ...(info!.axes.some((a) => a === 't' || a === 'time') ? { time: timeAxis(attrs, info!.time) } : {}),
    valueRange: null,
    isAbsent: () => false,
    close: () => reader.destroy?.(),
    readChunk: (level, brick, opts) => reader.read(level, brick, opts),
    sourceDecode: () => ({
      chunks: reader.counters.chunksDecoded,
      bytes: reader.counters.bytesDecoded,
      ms: reader.counters.decodeMs,
      nonFinite: reader.counters.nonFinite,
    }),
    ...(reader instanceof BrickWorkerPool ? { decodeQueue: () => reader.queue } : {}),
    sourceValueRange: (level) => {
      const r = reader.valueRanges[level];
      return r && r[0] <= r[1] ? [r[0], r[1]] : null;
    },
    readRanges: async (level, opts) => (levels[level].rangesPath && sidecar ? sidecar.read(level, opts) : null),
  };
}

/** The t axis shown (index, count) with its physical placement from the OME metadata. */
function timeAxis(attrs: Json, shown: SourceInfo['time']): NonNullable<ZfpStore['time']> {
  const ome = omeTimeAxisOf(attrs);
  return { ...shown, step: ome?.scale ?? null, origin: ome?.origin ?? 0, unit: ome?.unit ?? null };
}
