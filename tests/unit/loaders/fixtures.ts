// Extra LAS/TIFF files written by laspy/tifffile (make_fixtures.py) into a
// temporary folder, with the values those readers decode from them.
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { venvPython } from '../../helpers/python.ts';

export const sharedData = fileURLToPath(new URL('../../../../shared/data/', import.meta.url));

export interface Fixtures {
  dir: string;
  expected: { tiff: Record<string, any>; las: Record<string, any> };
  dispose(): void;
}

export function makeFixtures(): Fixtures {
  const dir = mkdtempSync(join(tmpdir(), 'zfpiso-loaders-'));
  const script = fileURLToPath(new URL('./make_fixtures.py', import.meta.url));
  execFileSync(venvPython(), [script, dir], { encoding: 'utf8', timeout: 300_000, stdio: ['ignore', 'pipe', 'pipe'] });
  const expected = JSON.parse(readFileSync(join(dir, 'expected.json'), 'utf8'));
  return { dir, expected, dispose: () => rmSync(dir, { recursive: true, force: true }) };
}

export function readBytes(path: string): Uint8Array<ArrayBuffer> {
  const b = readFileSync(path);
  return new Uint8Array(b.buffer as ArrayBuffer, b.byteOffset, b.byteLength);
}

export function sharedExpected(kind: 'las' | 'tiff' | 'swc'): Record<string, any> {
  return JSON.parse(readFileSync(join(sharedData, kind, 'expected.json'), 'utf8')).files;
}
