// `las FILE`: a LAS/LAZ file's header facts, bounds and first points, decoded
// with the LASzip Wasm module (the same module as the LIDAR page).
import { createHash } from 'node:crypto';
import { readFileSync } from 'node:fs';
import { basename } from 'node:path';
import { LasError, LasReader, scaled, type Vec3 } from '../../loaders/las.ts';
import { InputError, numberOption, requiredPositional, UsageError, type CliCommand } from '../command.ts';

export const lasCommand: CliCommand = {
  name: 'las',
  summary: 'LAS/LAZ header, bounds and first points (LASzip compiled to Wasm)',
  usage: 'las FILE [--chunk N]',
  options: { chunk: { type: 'string' } },
  async run(ctx, args) {
    const path = requiredPositional(args, 0, 'FILE');
    const chunk = numberOption(args, 'chunk') ?? 1 << 18;
    if (!Number.isInteger(chunk) || chunk < 1) throw new UsageError('--chunk must be a positive integer');
    let bytes: Uint8Array;
    try {
      bytes = readFileSync(path);
    } catch (e) {
      throw new InputError(`cannot read ${path}: ${(e as Error).message}`);
    }
    const name = basename(path);
    const t0 = performance.now();
    const reader = await LasReader.open(bytes, name).catch((e: unknown) => {
      throw e instanceof LasError ? new Error(e.message) : e;
    });
    try {
      const h = reader.header;
      const first3: Vec3[] = [];
      const min: Vec3 = [Infinity, Infinity, Infinity];
      const max: Vec3 = [-Infinity, -Infinity, -Infinity];
      const records = createHash('sha256');
      for (;;) {
        const c = reader.read(chunk, { xyz: true, records: true });
        if (!c) break;
        const xyz = c.xyz!;
        for (let i = 0; i < c.count; i++) {
          const p: Vec3 = [scaled(h, 0, xyz[3 * i]), scaled(h, 1, xyz[3 * i + 1]), scaled(h, 2, xyz[3 * i + 2])];
          if (first3.length < 3) first3.push(p);
          for (let a = 0; a < 3; a++) {
            if (p[a] < min[a]) min[a] = p[a];
            if (p[a] > max[a]) max[a] = p[a];
          }
        }
        records.update(c.records!);
        ctx.log(`read ${reader.pointsRead} of ${h.pointCount} points`);
      }
      const ms = performance.now() - t0;
      const warnings = reader.warnings;
      for (const w of warnings) console.error(`warning: ${w}`);
      const result = {
        file: path,
        pointCount: h.pointCount,
        version: h.version,
        pointFormat: h.pointFormat,
        pointRecordLength: h.pointRecordLength,
        compressed: h.compressed,
        hasRGB: h.hasRGB,
        hasGpsTime: h.hasGpsTime,
        scale: h.scale,
        offset: h.offset,
        /** As stored in the header. */
        bounds: h.bounds,
        /** Over the scaled coordinates of all points. */
        boundsPoints: h.pointCount > 0 ? { min, max } : null,
        first3,
        /** sha256 of the point records in uncompressed LAS layout (a .laz and its .las twin agree). */
        recordsSha256: records.digest('hex'),
        systemIdentifier: h.systemIdentifier,
        generatingSoftware: h.generatingSoftware,
        /** Problems that did not stop the file from loading (points outside the header's bounds, ...). */
        warnings,
        loadMs: ms,
      };
      console.log(
        `${name}: LAS ${h.version}, point format ${h.pointFormat}${h.compressed ? ' (LAZ)' : ''}, ${h.pointCount} points${h.hasRGB ? ', RGB' : ''}`,
      );
      console.log(`bounds   ${JSON.stringify(h.bounds.min)} .. ${JSON.stringify(h.bounds.max)}`);
      console.log(`decoded in ${ms.toFixed(1)} ms (${(((h.pointCount / ms) * 1e3) / 1e6).toFixed(2)} M points/s)`);
      return result;
    } finally {
      reader.close();
    }
  },
};
