// `decompress IN.zfp -o OUT.raw`: decodes a fixed-rate zfp file on the GPU to
// raw float32 (x fastest, little endian), slab by slab, so volumes larger
// than one storage binding work. Header-less streams need shape and rate in
// the name (`name_XxYxZ_float32.raw.crate4.zfp`) or --rate.
import { closeSync, openSync, readFileSync, writeSync } from 'node:fs';
import { basename } from 'node:path';
import { formatDims } from '../../core/naming.ts';
import { ZfpDecoder } from '../../zfp/decoder.ts';
import { openZfpStream, ZfpFormatError } from '../../zfp/format.ts';
import { ZfpGpuStream } from '../../zfp/gpu-stream.ts';
import { InputError, numberOption, requiredPositional, stringOption, UsageError, type CliCommand } from '../command.ts';

export const decompressCommand: CliCommand = {
  name: 'decompress',
  summary: 'fixed-rate zfp file -> raw float32 volume (GPU decoder)',
  usage: 'decompress IN.zfp -o OUT.raw [--rate R]',
  options: { out: { type: 'string', short: 'o' }, rate: { type: 'string' } },
  async run(ctx, args) {
    const input = requiredPositional(args, 0, 'IN.zfp');
    const output = stringOption(args, 'out');
    if (!output) throw new UsageError('give the output file with -o OUT.raw');
    let bytes: Uint8Array;
    try {
      bytes = new Uint8Array(readFileSync(input));
    } catch (e) {
      throw new InputError(`cannot read ${input}: ${(e as Error).message}`);
    }
    let info;
    try {
      info = openZfpStream(bytes, basename(input), { rate: numberOption(args, 'rate') });
    } catch (e) {
      if (e instanceof ZfpFormatError) throw new InputError(e.message);
      throw e;
    }
    const { device } = await ctx.gpu();
    const decoder = await ZfpDecoder.create(device);
    const t0 = performance.now();
    const stream = ZfpGpuStream.upload(device, info, bytes);
    const fd = openSync(output, 'w');
    let writeSeconds = 0;
    try {
      await decoder.readVolume(stream, {
        sink: (_z, slab) => {
          const t = performance.now();
          writeSync(fd, new Uint8Array(slab.buffer, slab.byteOffset, slab.byteLength));
          writeSeconds += (performance.now() - t) / 1000;
        },
      });
    } finally {
      closeSync(fd);
      stream.destroy();
      decoder.destroy();
    }
    const seconds = (performance.now() - t0) / 1000 - writeSeconds;
    const [nx, ny, nz] = info.dims;
    const outputBytes = nx * ny * nz * 4;
    const summary = {
      input,
      output,
      dims: info.dims,
      dtype: 'float32',
      rate: info.rate,
      bitsPerBlock: info.bitsPerBlock,
      header: info.hasHeader,
      blocks: info.blockCount,
      shards: stream.shards.length,
      compressedBytes: bytes.byteLength,
      outputBytes,
      seconds,
      gbPerSecond: outputBytes / seconds / 1e9,
      timing: 'wall time of upload, GPU decode and read-back (file I/O excluded); GB/s of float32 data',
    };
    ctx.log(
      `${output}: ${formatDims(info.dims)} float32 (${outputBytes} bytes) from rate ${info.rate}, ${seconds.toFixed(3)} s, ${summary.gbPerSecond.toFixed(3)} GB/s`,
    );
    return summary;
  },
};
