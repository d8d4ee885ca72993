// Tells what kind of file a user gave us, from its first bytes and its name,
// before any real parser runs. Used by `cli info` and the page's loader to
// pick a parser and to word errors.

import { parseVolumeName, type NameInfo } from '../core/naming.ts';
import { hasZfpMagic } from '../zfp/header.ts';

export type FileKind =
  | 'zfp' // zfp stream with the standard header
  | 'zfp-headerless' // `.zfp` without header: shape and rate must come from the name or options
  | 'raw' // uncompressed volume `name_XxYxZ_dtype.raw`
  | 'nrrd'
  | 'tiff'
  | 'las'
  | 'laz'
  | 'swc'
  | 'unknown';

export interface DetectedFile {
  kind: FileKind;
  name: NameInfo;
  /** Human-readable reason for the decision. */
  why: string;
}

function ascii(bytes: Uint8Array, start: number, length: number): string {
  return String.fromCharCode(...bytes.subarray(start, start + length));
}

/** `head` is the first bytes of the file (at least 16 when the file has them). */
export function detectFile(fileName: string, head: Uint8Array): DetectedFile {
  const lower = fileName.toLowerCase();
  const name = parseVolumeName(fileName);
  if (hasZfpMagic(head)) return { kind: 'zfp', name, why: 'starts with the zfp magic "zfp"' };
  if (ascii(head, 0, 4) === 'NRRD') return { kind: 'nrrd', name, why: 'starts with "NRRD"' };
  if (
    (head[0] === 0x49 && head[1] === 0x49 && (head[2] === 42 || head[2] === 43) && head[3] === 0) ||
    (head[0] === 0x4d && head[1] === 0x4d && head[2] === 0 && (head[3] === 42 || head[3] === 43))
  ) {
    return { kind: 'tiff', name, why: 'TIFF byte-order mark' };
  }
  if (ascii(head, 0, 4) === 'LASF') {
    return lower.endsWith('.laz')
      ? { kind: 'laz', name, why: 'LAS signature "LASF" and .laz extension' }
      : { kind: 'las', name, why: 'LAS signature "LASF"' };
  }
  if (lower.endsWith('.zfp')) return { kind: 'zfp-headerless', name, why: '.zfp file without the zfp magic' };
  if (lower.endsWith('.swc')) return { kind: 'swc', name, why: '.swc extension' };
  if (lower.endsWith('.raw')) return { kind: 'raw', name, why: '.raw extension' };
  return { kind: 'unknown', name, why: 'no known signature or extension' };
}
