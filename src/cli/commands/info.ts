// `info FILE [--rate R] [--stream-budget MB]`: what a file is (kind, shape,
// type; for zfp the mode, rate and header). For a volume that would be
// compressed here (raw with its shape in the name, NRRD, TIFF stack) also the
// rate chosen from its data and the error it gives, as `extract` and the page
// would choose it (src/zfp/rate-choice.ts; the GPU tries rates on a sample),
// or the error at --rate R. For a Zarr store: its levels, and for a store
// of lossless chunks its codecs, type, axes, bricks and rate.
import { closeSync, openSync, readFileSync, readSync, statSync } from 'node:fs';
import { basename } from 'node:path';
import { describeFile } from '../../formats/describe.ts';
import { countNonFinite, nonFiniteTotal, replaceNonFinite } from '../../volume/non-finite.ts';
import { chooseVolumeRate, inspectVolumeFile, VolumeFileError } from '../../volume/open-volume.ts';
import { describeRateChoice, rateErrorRecord } from '../../zfp/rate-choice.ts';
import { type CliCommand, InputError, numberOption, requiredPositional } from '../command.ts';
import { streamBudgetOption } from './extract.ts';
import { isStoreInput } from '../../store/cli-input.ts';
import { storeRateChooser } from '../../store/rate.ts';
import { StoreError } from '../../store/zarr/errors.ts';
import { storeForLocation } from '../../store/zarr/node-store.ts';
import { openStore } from '../../store/zarr/open-store.ts';

/** A store: its levels and, for a store of lossless chunks, codecs, type, axes and the rate chosen from the data (or --rate). */
async function storeInfo(
  ctx: Parameters<CliCommand['run']>[0],
  path: string,
  opts: { rate?: number; time?: number; channel?: number },
): Promise<Record<string, unknown>> {
  let store;
  try {
    const gpu = await ctx.gpu();
    store = await openStore(storeForLocation(path), path, { ...opts, chooseRate: storeRateChooser(gpu) });
  } catch (e) {
    if (e instanceof StoreError) throw new InputError(e.message, { cause: e });
    throw e;
  }
  for (const note of store.notes) ctx.log(`note: ${note}`);
  const levels = store.levels.map((l) => ({
    level: l.index,
    path: l.path,
    dims: l.layout.dims,
    chunkEdge: l.layout.chunkEdge,
    chunks: l.chunkCount,
    rate: l.layout.rate,
    storedBytes: l.storedBytes,
    ranges: l.rangesPath !== null,
    unusable: l.unusable,
  }));
  const src = store.source;
  console.log(
    `kind           ${src ? `${src.format} store of lossless chunks (${src.codecs.join(' + ') || 'uncompressed'}, ${src.dtype})` : 'Zarr store of zfp chunks'}`,
  );
  if (src)
    console.log(
      `chunks         ${src.chunkShape.join('x')} (${src.axes.join('')}), read as ${src.bricks}; time ${src.time.index} of ${src.time.count}, channel ${src.channel.index} of ${src.channel.count}`,
    );
  console.log(`voxel size     ${store.voxelSize.join(' x ')}${store.unit ? ` ${store.unit}` : ''}`);
  for (const l of levels)
    console.log(
      `level ${String(l.level).padEnd(8)} ${l.dims.join('x')}, ${l.chunks} chunks of ${l.chunkEdge}^3 at rate ${l.rate}${l.ranges ? ', ranges' : ''}${l.unusable ? ` (cannot be shown: ${l.unusable})` : ''}`,
    );
  store.close?.();
  return {
    file: path,
    kind: 'zarr-store',
    source: src,
    voxelSize: store.voxelSize,
    unit: store.unit,
    valueRange: store.valueRange,
    levels,
    notes: store.notes,
  };
}

/** First bytes of a file, for signatures and headers. */
function readHead(path: string, length: number): Uint8Array {
  const fd = openSync(path, 'r');
  try {
    const head = new Uint8Array(length);
    const n = readSync(fd, head, 0, length, 0);
    return head.subarray(0, n);
  } finally {
    closeSync(fd);
  }
}

export const infoCommand: CliCommand = {
  name: 'info',
  summary: 'file kind, dims, dtype; for zfp the mode, rate and header presence; for raw/NRRD/TIFF the rate chosen from the data',
  usage: 'info FILE|STORE [--rate R | --stream-budget MB] [--time T] [--channel C]',
  options: { rate: { type: 'string' }, 'stream-budget': { type: 'string' }, time: { type: 'string' }, channel: { type: 'string' } },
  async run(ctx, args) {
    const path = requiredPositional(args, 0, 'FILE');
    if (isStoreInput(path))
      return storeInfo(ctx, path, {
        rate: numberOption(args, 'rate'),
        time: numberOption(args, 'time'),
        channel: numberOption(args, 'channel'),
      });
    let stat;
    try {
      stat = statSync(path);
    } catch (e) {
      throw new InputError(`cannot read ${path}: ${(e as Error).message}`);
    }
    if (stat.isDirectory())
      throw new InputError(`${path}: a folder, but not a Zarr store (no zarr.json, .zgroup or .zarray at its root) nor a file`);
    const size = stat.size;
    const rate = numberOption(args, 'rate');
    const maxStreamBytes = streamBudgetOption(args);
    const description = describeFile(basename(path), size, readHead(path, 4096), { rate });
    let rateRecord: Record<string, unknown> = {};
    if (['raw', 'nrrd', 'tiff'].includes(description.kind) && description.problems.length === 0) {
      try {
        const bytes = new Uint8Array(readFileSync(path));
        const facts = await inspectVolumeFile(basename(path), bytes, { reader: 'command' });
        const data0 = facts.kind === 'nrrd' ? facts.nrrd?.data : facts.kind === 'tiff' ? facts.samples : bytes;
        if (facts.compresses && facts.dims && facts.dtype && data0) {
          let data = data0;
          const nonFinite = countNonFinite(data, facts.dtype);
          if (nonFinite && nonFiniteTotal(nonFinite) > 0 && nonFiniteTotal(nonFinite) < nonFinite.values)
            data = replaceNonFinite(data, facts.dtype as 'float32' | 'float64', nonFinite);
          const { device } = await ctx.gpu();
          const choice = await chooseVolumeRate(device, data, facts.dtype, facts.dims, { rate, maxStreamBytes, fileName: basename(path) });
          description.rate = choice.rate;
          rateRecord = { rateError: rateErrorRecord(choice) };
          ctx.log(`note: ${basename(path)}: ${describeRateChoice(choice)}`);
        }
      } catch (e) {
        if (e instanceof VolumeFileError || e instanceof RangeError) throw new InputError(e.message, { cause: e });
        throw e;
      }
    }
    for (const [k, v] of Object.entries(description)) {
      if (v === undefined) continue;
      console.log(`${k.padEnd(14)} ${typeof v === 'object' ? JSON.stringify(v) : String(v)}`);
    }
    return { file: path, ...description, ...rateRecord };
  },
};
