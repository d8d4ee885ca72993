// `compress IN [--dims X,Y,Z] [--dtype T] [--rate R] -o OUT.zfp`: compresses a
// raw volume (x fastest, little endian; uint8/int8/uint16/int16/float32/
// float64, converted to float32) to a fixed-rate zfp file on the GPU. Shape
// and type come from the name (`name_XxYxZ_dtype.raw`) unless given; the rate
// is chosen from the data (src/zfp/rate-choice.ts) unless given. Either way
// the stream's error against the input is measured and recorded.
import { readFileSync, writeFileSync } from 'node:fs';
import { basename } from 'node:path';
import { DTYPE_BYTES, DTYPES, isDType, type DType } from '../../core/dtype.ts';
import { formatDims, parseVolumeName, type Dims } from '../../core/naming.ts';
import { allNonFiniteMessage, countNonFinite, nonFiniteNotice, nonFiniteTotal, replaceNonFinite } from '../../volume/non-finite.ts';
import { ZfpEncoder } from '../../zfp/encoder.ts';
import { planZfpStream, ZfpFormatError } from '../../zfp/format.ts';
import { chooseRate, describeRateChoice, rateErrorRecord, type RateChoice } from '../../zfp/rate-choice.ts';
import { ZfpErrorMeter } from '../../zfp/stream-error.ts';
import { streamBudgetOption } from './extract.ts';
import { InputError, numberListOption, numberOption, requiredPositional, stringOption, UsageError, type CliCommand } from '../command.ts';

export const compressCommand: CliCommand = {
  name: 'compress',
  summary: 'raw volume -> fixed-rate zfp file (GPU encoder; zfpy reads the result)',
  usage: 'compress IN [--dims X,Y,Z] [--dtype T] [--rate R | --stream-budget MB] -o OUT.zfp [--headerless]',
  options: {
    dims: { type: 'string' },
    dtype: { type: 'string' },
    rate: { type: 'string' },
    'stream-budget': { type: 'string' },
    out: { type: 'string', short: 'o' },
    headerless: { type: 'boolean' },
  },
  async run(ctx, args) {
    const input = requiredPositional(args, 0, 'IN (a raw volume)');
    const output = stringOption(args, 'out');
    if (!output) throw new UsageError('give the output file with -o OUT.zfp');
    const rate = numberOption(args, 'rate');
    const maxStreamBytes = streamBudgetOption(args);
    const name = parseVolumeName(basename(input));
    const dimList = numberListOption(args, 'dims');
    let dims: Dims | undefined = name.dims;
    if (dimList) {
      if (dimList.length !== 3 || dimList.some((n) => !Number.isInteger(n) || n < 1))
        throw new UsageError('--dims must be three positive integers X,Y,Z');
      dims = [dimList[0], dimList[1], dimList[2]];
    }
    if (!dims) throw new UsageError(`${input}: the name carries no shape (name_XxYxZ_dtype.raw): give --dims X,Y,Z`);
    const dtypeText = stringOption(args, 'dtype');
    if (dtypeText !== undefined && !isDType(dtypeText))
      throw new UsageError(`--dtype must be one of ${DTYPES.join(', ')} (got "${dtypeText}")`);
    const dtype: DType | undefined = (dtypeText as DType | undefined) ?? name.dtype;
    if (!dtype) throw new UsageError(`${input}: the name carries no type: give --dtype (${DTYPES.join(', ')})`);
    let bytes: Uint8Array;
    try {
      bytes = new Uint8Array(readFileSync(input));
    } catch (e) {
      throw new InputError(`cannot read ${input}: ${(e as Error).message}`);
    }
    const expect = dims[0] * dims[1] * dims[2] * DTYPE_BYTES[dtype];
    if (bytes.byteLength !== expect)
      throw new InputError(`${input}: ${formatDims(dims)} ${dtype} is ${expect} bytes, the file has ${bytes.byteLength}`);

    try {
      if (rate !== undefined) planZfpStream(basename(input), dims, rate, !args.values.headerless); // user mistakes before any GPU work
    } catch (e) {
      if (e instanceof ZfpFormatError) throw new UsageError(e.message);
      throw e;
    }
    // zfp cannot store NaN/Inf: replaced as the page and `extract` do (src/volume/non-finite.ts), and said so.
    const nonFinite = countNonFinite(bytes, dtype);
    const notes: string[] = [];
    if (nonFinite && nonFiniteTotal(nonFinite) > 0) {
      if (nonFiniteTotal(nonFinite) === nonFinite.values) throw new InputError(`${input}: ${allNonFiniteMessage(nonFinite)}`);
      bytes = replaceNonFinite(bytes, dtype as 'float32' | 'float64', nonFinite);
      notes.push(`${input}: ${nonFiniteNotice(nonFinite)}`);
      ctx.log(`note: ${notes[0]}`);
    }
    const { device } = await ctx.gpu();
    const encoder = await ZfpEncoder.create(device);
    const meter = await ZfpErrorMeter.create(device);
    try {
      let choice: RateChoice;
      try {
        choice = await chooseRate(encoder, meter, bytes, dtype, dims, { rate, maxStreamBytes, fileName: basename(input) });
      } catch (e) {
        if (e instanceof ZfpFormatError || e instanceof RangeError) throw new InputError(e.message);
        throw e;
      }
      if (choice.warning) {
        notes.push(choice.warning);
        ctx.log(`note: ${choice.warning}`);
      }
      const t0 = performance.now();
      let result;
      try {
        const made = await encoder.compressMeasured(bytes, dtype, dims, choice.rate, meter, {
          header: !args.values.headerless,
          fileName: basename(input),
        });
        choice.stream = made.error;
        try {
          result = { bytes: await made.stream.readBytes(), info: made.stream.info };
        } finally {
          made.stream.destroy();
        }
      } catch (e) {
        if (e instanceof ZfpFormatError) throw new InputError(e.message);
        throw e;
      }
      const seconds = (performance.now() - t0) / 1000;
      ctx.log(`note: ${basename(input)}: ${describeRateChoice(choice)}`);
      writeFileSync(output, result.bytes);
      const floatBytes = dims[0] * dims[1] * dims[2] * 4;
      const info = result.info;
      const summary = {
        input,
        output,
        dims,
        dtype,
        rate: info.rate,
        ...(rate !== undefined ? { requestedRate: rate } : {}),
        rateError: rateErrorRecord(choice),
        bitsPerBlock: info.bitsPerBlock,
        header: info.hasHeader,
        blocks: info.blockCount,
        inputBytes: bytes.byteLength,
        outputBytes: result.bytes.byteLength,
        compressionRatio: floatBytes / result.bytes.byteLength,
        seconds,
        gbPerSecond: floatBytes / seconds / 1e9,
        notes,
        timing:
          'wall time of upload, GPU encode, error measurement and read-back (file I/O and the rate choice, rateError.ms, excluded); GB/s of float32 data',
      };
      ctx.log(
        `${output}: ${formatDims(dims)} ${dtype} -> ${result.bytes.byteLength} bytes at rate ${info.rate} (${info.bitsPerBlock} bits/block${info.hasHeader ? ', zfp header' : ', no header'}), ` +
          `${seconds.toFixed(3)} s, ${summary.gbPerSecond.toFixed(3)} GB/s`,
      );
      return summary;
    } finally {
      encoder.destroy();
      meter.destroy();
    }
  },
};
