// `info FILE [--rate R] [--stream-budget MB]`: what a file is (kind, shape,
// type; for zfp the mode, rate and header). For a volume that would be
// compressed here (raw with its shape in the name, NRRD, TIFF stack) also the
// rate chosen from its data and the error it gives, as `extract` and the page
// would choose it (src/zfp/rate-choice.ts; the GPU tries rates on a sample),
// or the error at --rate R.
import { closeSync, openSync, readFileSync, readSync, statSync } from 'node:fs';
import { basename } from 'node:path';
import { describeFile } from '../../formats/describe.ts';
import { countNonFinite, nonFiniteTotal, replaceNonFinite } from '../../volume/non-finite.ts';
import { chooseVolumeRate, inspectVolumeFile, VolumeFileError } from '../../volume/open-volume.ts';
import { describeRateChoice, rateErrorRecord } from '../../zfp/rate-choice.ts';
import { type CliCommand, InputError, numberOption, requiredPositional } from '../command.ts';
import { streamBudgetOption } from './extract.ts';

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
  usage: 'info FILE [--rate R | --stream-budget MB]',
  options: { rate: { type: 'string' }, 'stream-budget': { type: 'string' } },
  async run(ctx, args) {
    const path = requiredPositional(args, 0, 'FILE');
    const size = statSync(path).size;
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
