// The CLI commands end to end on the shared files: compress (uint8 -> zfp
// with header, as zfpy writes it), decompress (as zfpy decodes it), info,
// a file that is not what it says reported with exit code 1 (a data failure),
// a wrong command line with exit code 2.
import { spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { describe, expect, it } from 'vitest';
import { repoRoot, runPython, sharedData } from '../../helpers/python.ts';

function cli(...args: string[]) {
  const r = spawnSync(
    process.execPath,
    ['--import', join(repoRoot, 'scripts/register-node-loaders.mjs'), join(repoRoot, 'src/cli/main.ts'), ...args],
    {
      encoding: 'utf8',
      timeout: 240_000,
    },
  );
  return { status: r.status, stderr: r.stderr, stdout: r.stdout };
}

describe('zfp CLI', () => {
  const dir = mkdtempSync(join(tmpdir(), 'zfp-cli-'));
  const raw = join(sharedData, 'volumes', 'neghip_66x66x66_uint8.raw');

  it('compress, info and decompress agree with zfpy', () => {
    const zfp = join(dir, 'neghip.zfp');
    const c = cli('compress', raw, '--rate', '3.3', '-o', zfp, '--json', join(dir, 'c.json'));
    expect(c.status, c.stderr).toBe(0);
    const cj = JSON.parse(readFileSync(join(dir, 'c.json'), 'utf8'));
    expect(cj).toMatchObject({
      dims: [66, 66, 66],
      dtype: 'uint8',
      rate: 211 / 64,
      bitsPerBlock: 211,
      header: true,
      outputBytes: readFileSync(zfp).byteLength,
    });
    expect(cj.gbPerSecond).toBeGreaterThan(0);

    const i = cli('info', zfp, '--json', join(dir, 'i.json'));
    expect(i.status, i.stderr).toBe(0);
    expect(JSON.parse(readFileSync(join(dir, 'i.json'), 'utf8'))).toMatchObject({
      kind: 'zfp',
      dims: [66, 66, 66],
      dtype: 'float32',
      bitsPerBlock: 211,
      payloadBitOffset: 96,
      problems: [],
    });

    const out = join(dir, 'neghip.raw');
    const d = cli('decompress', zfp, '-o', out, '--json', join(dir, 'd.json'));
    expect(d.status, d.stderr).toBe(0);
    expect(JSON.parse(readFileSync(join(dir, 'd.json'), 'utf8'))).toMatchObject({
      dims: [66, 66, 66],
      outputBytes: 66 ** 3 * 4,
      bitsPerBlock: 211,
    });

    const verdict = runPython(
      `
import sys, numpy as np, zfpy
raw, zfp, out = sys.argv[1:4]
a = np.fromfile(raw, np.uint8).reshape(66, 66, 66).astype(np.float32)
ours = open(zfp, 'rb').read()
same = zfpy.compress_numpy(a, rate=3.3, write_header=True) == ours
dec = zfpy.decompress_numpy(ours)
print(same, np.array_equal(dec.view(np.uint32), np.fromfile(out, '<u4').reshape(66, 66, 66)))
`,
      [raw, zfp, out],
    );
    expect(verdict.trim()).toBe('True True');
  });

  it('a bad input file exits 1 without the usage; a wrong command line exits 2', () => {
    const bad = cli('decompress', join(sharedData, 'volumes', 'fuel_64x64x64_float8.zfp'), '--rate', '8', '-o', join(dir, 'x.raw'));
    expect(bad.status).toBe(1);
    expect(bad.stderr).not.toMatch(/usage:/);
    expect(bad.stderr).toMatch(
      /fuel_64x64x64_float8\.zfp: a header-less fixed-rate 8 stream of 64x64x64 float32 is 262144 bytes .* the file has 5008/,
    );
    // No --rate: chosen from the data (src/zfp/rate-choice.ts), said on stderr and in the record.
    const noRate = cli('compress', raw, '-o', join(dir, 'y.zfp'), '--json', join(dir, 'y.json'));
    expect(noRate.status, noRate.stderr).toBe(0);
    expect(noRate.stderr).toMatch(
      /note: neghip_66x66x66_uint8\.raw: rate 8 chosen from the data: sampled RMS error .* <= 0\.15 \(0\.15 of a source step \(uint8\)\)/,
    );
    const y = JSON.parse(readFileSync(join(dir, 'y.json'), 'utf8'));
    expect(y).toMatchObject({ rate: 8, rateError: { how: 'chosen', bound: 0.15, candidateBlocks: 17 ** 3, structured: true } });
    expect(y.rateError.sampleBlocks).toBeLessThan(17 ** 3);
    expect(y.rateError.rms).toBeGreaterThan(0);
    expect(y.rateError.rms).toBeLessThanOrEqual(0.15);
    // info on the raw file: the same choice, without compressing it
    const info = cli('info', raw, '--json', join(dir, 'ri.json'));
    expect(info.status, info.stderr).toBe(0);
    expect(JSON.parse(readFileSync(join(dir, 'ri.json'), 'utf8'))).toMatchObject({ kind: 'raw', rate: 8, rateError: { how: 'chosen' } });
    const badBudget = cli('compress', raw, '--stream-budget=-3', '-o', join(dir, 'z.zfp'));
    expect(badBudget.status).toBe(2);
    expect(badBudget.stderr).toMatch(/--stream-budget must be a positive number of MB/);
  });
});
