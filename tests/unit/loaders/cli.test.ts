// The `las` and `tiff` CLI commands against laspy/tifffile's expected.json:
// every shared file in process, and the real command line once each.
import { spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, describe, expect, test } from 'vitest';
import type { CliContext, ParsedArgs } from '../../../src/cli/command.ts';
import { lasCommand } from '../../../src/cli/commands/las.ts';
import { tiffCommand } from '../../../src/cli/commands/tiff.ts';
import { repoRoot } from '../../helpers/python.ts';
import { sharedData, sharedExpected } from './fixtures.ts';

const ctx: CliContext = {
  gpu: () => Promise.reject(new Error('the loaders need no GPU')),
  log: () => undefined,
};
const args = (...positionals: string[]): ParsedArgs => ({ values: {}, positionals });
const quiet = <T>(fn: () => Promise<T>): Promise<T> => {
  const log = console.log;
  console.log = () => undefined;
  return fn().finally(() => (console.log = log));
};

describe('las command', () => {
  const expected = sharedExpected('las');
  test.each(Object.keys(expected))('%s', async (name) => {
    const e = expected[name];
    const r = (await quiet(() => lasCommand.run(ctx, args(join(sharedData, 'las', name))))) as Record<string, any>;
    expect(r.pointCount).toBe(e.point_count);
    expect(r.version).toBe(e.las_version);
    expect(r.pointFormat).toBe(e.point_format);
    expect(r.hasRGB).toBe(e.has_rgb);
    expect(r.first3).toEqual(e.first3_xyz_scaled);
    for (let a = 0; a < 3; a++) {
      expect(r.bounds.min[a]).toBeCloseTo(e.bounds_header.min[a], 6);
      expect(r.bounds.max[a]).toBeCloseTo(e.bounds_header.max[a], 6);
    }
    expect(r.boundsPoints).toEqual(e.bounds_points);
    expect(r.recordsSha256).toBe(e.points_record_sha256);
  });
});

describe('tiff command', () => {
  const expected = sharedExpected('tiff');
  test.each(Object.keys(expected))('%s', async (name) => {
    const e = expected[name];
    const r = (await quiet(() => tiffCommand.run(ctx, args(join(sharedData, 'tiff', name))))) as Record<string, any>;
    expect(r.pages).toBe(e.pages);
    expect(r.width).toBe(e.width);
    expect(r.height).toBe(e.height);
    expect(r.bitsPerSample).toBe(e.bits_per_sample);
    expect(r.sampleFormat).toBe(e.sample_format.name);
    expect(r.compression).toBe(e.compression.name);
    expect(r.sha256).toBe(e.decoded.sha256_pyxs);
    expect(r.min).toBe(e.decoded.min);
    expect(r.max).toBe(e.decoded.max);
    expect(r.mean).toBeCloseTo(e.decoded.mean, 9);
  });
});

describe('the command line', () => {
  const out = mkdtempSync(join(tmpdir(), 'zfpiso-cli-'));
  afterAll(() => rmSync(out, { recursive: true, force: true }));
  const cli = (...argv: string[]) =>
    spawnSync(process.execPath, [join(repoRoot, 'scripts', 'cli.mjs'), ...argv], { cwd: repoRoot, encoding: 'utf8', timeout: 120_000 });

  test('las and tiff write --json; a bad file exits 1 with a message naming it', () => {
    const laz = cli('las', join(sharedData, 'las', 'laspy_simple.laz'), '--json', join(out, 'las.json'));
    expect(laz.status, laz.stderr).toBe(0);
    const las = JSON.parse(readFileSync(join(out, 'las.json'), 'utf8'));
    expect(Object.keys(las)).toEqual(expect.arrayContaining(['pointCount', 'version', 'pointFormat', 'bounds', 'first3', 'hasRGB']));
    expect(las.first3).toEqual(sharedExpected('las')['laspy_simple.laz'].first3_xyz_scaled);

    const tif = cli('tiff', join(sharedData, 'tiff', 'imagejs_grey8-multi.tif'), '--json', join(out, 'tiff.json'));
    expect(tif.status, tif.stderr).toBe(0);
    const t = JSON.parse(readFileSync(join(out, 'tiff.json'), 'utf8'));
    expect(Object.keys(t)).toEqual(
      expect.arrayContaining(['pages', 'width', 'height', 'bitsPerSample', 'sampleFormat', 'compression', 'sha256', 'min', 'max', 'mean']),
    );
    expect(t.sha256).toBe(sharedExpected('tiff')['imagejs_grey8-multi.tif'].decoded.sha256_pyxs);

    const bad = cli('las', join(sharedData, 'tiff', 'imagejs_stack.tif'));
    expect(bad.status).toBe(1);
    expect(bad.stderr).toMatch(/error: imagejs_stack\.tif: not a LAS\/LAZ file/);
    const missing = cli('tiff', join(out, 'nope.tif'));
    expect(missing.status).toBe(1);
    expect(missing.stderr).toMatch(/cannot read .*nope\.tif/);
  });
});
