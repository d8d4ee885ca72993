// NRRD files written by pynrrd (an independent implementation) read back to
// the same samples; malformed files are rejected with their reason.
import { mkdtempSync, readFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { describe, expect, it } from 'vitest';
import { parseNrrd } from '../../../src/volume/nrrd.ts';
import { runPython } from '../../helpers/python.ts';

const WRITE = `
import sys, numpy as np, nrrd
out, dtype, encoding, endian = sys.argv[1:5]
rng = np.random.default_rng(7)
shape_xyz = (5, 3, 7)
a = (rng.random(shape_xyz[::-1]) * 200 - 50).astype(dtype)   # [z][y][x]
# pynrrd takes arrays indexed [x][y][z] in Fortran order by default
nrrd.write(out + '.nrrd', a.transpose(), header={'encoding': encoding, 'endian': endian, 'spacings': [0.5, 1.0, 2.0]})
a.astype(a.dtype.newbyteorder('<')).tofile(out + '.raw')
`;

describe('NRRD reader', () => {
  const dir = mkdtempSync(join(tmpdir(), 'nrrd-'));
  const cases: [string, string, string, string][] = [
    ['uint8', 'raw', 'little', 'uint8'],
    ['int16', 'raw', 'big', 'int16'],
    ['uint16', 'gzip', 'little', 'uint16'],
    ['float32', 'raw', 'big', 'float32'],
    ['float64', 'gzip', 'big', 'float64'],
    ['int8', 'raw', 'little', 'int8'],
  ];
  for (const [np, encoding, endian, dtype] of cases) {
    it(`reads ${np} ${encoding} ${endian}-endian as pynrrd wrote it`, async () => {
      const base = join(dir, `${np}-${encoding}-${endian}`);
      runPython(WRITE, [base, np, encoding, endian]);
      const volume = await parseNrrd(new Uint8Array(readFileSync(`${base}.nrrd`)));
      expect(volume.dims).toEqual([5, 3, 7]);
      expect(volume.dtype).toBe(dtype);
      expect(volume.spacing).toEqual([0.5, 1, 2]);
      expect(Buffer.from(volume.data).equals(readFileSync(`${base}.raw`))).toBe(true);
    });
  }

  const header = (lines: string[]) => new TextEncoder().encode(['NRRD0004', ...lines, '', ''].join('\n'));
  const bad: [string, Uint8Array, RegExp][] = [
    ['not NRRD', new TextEncoder().encode('hello world\n\n'), /not a NRRD file/],
    ['detached data', header(['type: float', 'dimension: 3', 'sizes: 2 2 2', 'encoding: raw', 'data file: x.raw']), /detached/],
    ['int32', header(['type: int', 'dimension: 3', 'sizes: 2 2 2', 'encoding: raw']), /sample type "int"/],
    ['2D', header(['type: float', 'dimension: 2', 'sizes: 2 2', 'encoding: raw']), /only 3D/],
    ['ascii', header(['type: float', 'dimension: 3', 'sizes: 2 2 2', 'encoding: ascii']), /encoding "ascii"/],
    ['truncated', header(['type: float', 'dimension: 3', 'sizes: 2 2 2', 'encoding: raw']), /truncated/],
  ];
  for (const [name, bytes, message] of bad) {
    it(`rejects ${name}`, async () => {
      await expect(parseNrrd(bytes)).rejects.toThrow(message);
    });
  }
});
