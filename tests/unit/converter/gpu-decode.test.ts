// The converter's chunks decode on our GPU decoder exactly as zfpy decodes
// them: `npm run convert` writes a store from a shared volume (partial chunks
// and partial zfp blocks at the far edges), and every chunk file of every
// level, as stored, goes through src/zfp's WGSL decoder and is compared bit
// for bit with zfpy.decompress_numpy of the same bytes (what zarr-python's
// numcodecs.zfpy codec does when it reads the chunk).
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readdirSync, readFileSync, rmSync, statSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, relative } from 'node:path';
import { afterAll, beforeAll, describe, expect } from 'vitest';
import { ZfpDecoder } from '../../../src/zfp/decoder.ts';
import { loadZfpStream } from '../../../src/zfp/gpu-stream.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { repoRoot, sharedData } from '../../helpers/python.ts';
import { firstDifference } from '../zfp/vectors.ts';

const work = mkdtempSync(join(tmpdir(), 'zfpzarr-gpu-'));
const store = join(work, 'neghip.zarr');

function chunkFiles(dir: string): string[] {
  const out: string[] = [];
  for (const name of readdirSync(dir)) {
    const path = join(dir, name);
    if (statSync(path).isDirectory()) out.push(...chunkFiles(path));
    else if (/^\d+$/.test(name)) out.push(path);
  }
  return out;
}

beforeAll(() => {
  // npm run convert's script: makes the converter's Python environment on first use
  execFileSync(
    process.execPath,
    [
      join(repoRoot, 'scripts/convert.mjs'),
      join(sharedData, 'volumes/neghip_66x66x66_uint8.raw'),
      '--out',
      store,
      '--chunk',
      '32',
      '--rate',
      '4,6',
      '--quiet',
    ],
    { cwd: repoRoot, stdio: 'pipe', timeout: 900_000 },
  );
  // zfpy's decode of every chunk file, written next to it as .f32
  const python = join(repoRoot, '.venv-converter/bin/python');
  execFileSync(
    python,
    [
      '-c',
      `
import sys, pathlib, zfpy
for p in pathlib.Path(sys.argv[1]).rglob('*'):
    if p.is_file() and p.name.isdigit() and '/ranges/' not in str(p):
        zfpy.decompress_numpy(p.read_bytes()).tofile(str(p) + '.f32')
`,
      store,
    ],
    { encoding: 'utf8' },
  );
}, 900_000);

afterAll(() => rmSync(work, { recursive: true, force: true }));

describe('converter chunks on the GPU decoder', () => {
  gpuTest('every chunk of every level decodes bit for bit as zfpy decodes it', async ({ gpu }) => {
    const decoder = await ZfpDecoder.create(gpu.device);
    const levels = ['0', '1', '2'];
    const seen: Record<string, number> = {};
    for (const level of levels) {
      const files = chunkFiles(join(store, level, 'c'));
      seen[level] = files.length;
      for (const file of files) {
        const name = relative(store, file);
        const stream = loadZfpStream(gpu.device, new Uint8Array(readFileSync(file)), name);
        expect(stream.info.dims, name).toEqual([32, 32, 32]);
        expect(stream.info.rate, name).toBe(level === '0' ? 4 : 6);
        const decoded = (await decoder.readVolume(stream))!;
        const reference = new Uint8Array(readFileSync(`${file}.f32`));
        expect(firstDifference(new Uint8Array(decoded.buffer), reference), name).toBe('identical');
        stream.destroy();
      }
    }
    // 66^3 in 32^3 chunks: 3^3 at level 0, 33^3 -> 2^3, 17^3 -> 1
    expect(seen).toEqual({ 0: 27, 1: 8, 2: 1 });
    decoder.destroy();
  });
});
