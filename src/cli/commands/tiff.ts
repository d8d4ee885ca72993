// `tiff FILE...`: a TIFF (or a stack of files, ordered by name) decoded with
// the libtiff Wasm module (the same module as the neuron page): page facts and
// the sha256/min/max/mean of the samples laid out [page][y][x][sample].
import { createHash } from 'node:crypto';
import { readFileSync } from 'node:fs';
import { basename } from 'node:path';
import { loadTiffStack, sampleStats, TiffError, TiffReader, type TiffSource } from '../../loaders/tiff.ts';
import { InputError, UsageError, type CliCommand } from '../command.ts';

export const tiffCommand: CliCommand = {
  name: 'tiff',
  summary: 'TIFF image/stack facts and sample hash (libtiff compiled to Wasm); several files = one stack',
  usage: 'tiff FILE [FILE...]',
  options: {},
  async run(ctx, args) {
    if (args.positionals.length === 0) throw new UsageError('missing FILE');
    const sources: TiffSource[] = args.positionals.map((path) => {
      try {
        return { name: basename(path), bytes: readFileSync(path) };
      } catch (e) {
        throw new InputError(`cannot read ${path}: ${(e as Error).message}`);
      }
    });
    try {
      // Directory count of every file (the volume may leave out thumbnails).
      let ifds = 0;
      for (const s of sources) {
        const r = await TiffReader.open(s.bytes, s.name);
        ifds += r.pageCount;
        r.close();
      }
      const t0 = performance.now();
      const v = await loadTiffStack(sources, {
        onProgress: (done, total) => (done === total || done % 64 === 0) && ctx.log(`decoded ${done} of ${total} pages`),
      });
      const ms = performance.now() - t0;
      const p = v.pages[0];
      const sha256 = createHash('sha256')
        .update(new Uint8Array(v.data.buffer, v.data.byteOffset, v.data.byteLength))
        .digest('hex');
      const stats = sampleStats(v.data);
      const result = {
        files: args.positionals,
        pages: v.pages.length,
        ifds,
        width: p.width,
        height: p.height,
        samplesPerPixel: p.samplesPerPixel,
        bitsPerSample: p.bitsPerSample,
        sampleFormat: p.sampleFormatName,
        sampleFormatCode: p.sampleFormat,
        compression: p.compressionName,
        compressionCode: p.compression,
        photometric: p.photometricName,
        planarConfig: p.planarConfig,
        tiled: p.tiled,
        dtype: v.dtype,
        /** sha256 of the samples laid out [page][y][x][sample], little-endian. */
        sha256,
        ...stats,
        spacing: v.spacing ?? null,
        unit: v.unit ?? null,
        imagej: v.imagej !== undefined,
        loadMs: ms,
      };
      console.log(
        `${v.files.length > 1 ? `${v.files.length} files` : v.files[0]}: ${p.width}×${p.height}×${v.pages.length} ${v.dtype}${p.samplesPerPixel > 1 ? ` ×${p.samplesPerPixel}` : ''}, ${p.compressionName}`,
      );
      console.log(`min ${stats.min}  max ${stats.max}  mean ${stats.mean}`);
      console.log(`sha256 ${sha256}`);
      console.log(`decoded in ${ms.toFixed(1)} ms`);
      return result;
    } catch (e) {
      // A bad file is the user's input, not a crash: its message names the file.
      if (e instanceof TiffError) throw new Error(e.message);
      throw e;
    }
  },
};
