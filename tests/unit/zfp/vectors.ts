// The shared zfp test vectors (made by zfp 1.0.1 itself): see ../shared/data/README.md.
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { sharedData } from '../../helpers/python.ts';
import { mulberry32 } from '../../../src/util/random.ts';

export const vectorDir = join(sharedData, 'zfp-vectors');

export interface ZfpVector {
  name: string;
  dims_xyz: [number, number, number];
  rate: number;
  bits_per_block: number;
  nblocks: number;
  compressed: string;
  input: string;
  decoded: string;
  header_hex: string;
  with_header: { file: string; bytes: number; payload_offset_bytes: number };
}

export const vectors: ZfpVector[] = JSON.parse(readFileSync(join(vectorDir, 'manifest.json'), 'utf8')).vectors;

export function readVector(file: string): Uint8Array {
  return new Uint8Array(readFileSync(join(vectorDir, file)));
}

/** Byte equality with the index of the first difference in the message. */
export function firstDifference(a: Uint8Array, b: Uint8Array): string {
  if (a.byteLength !== b.byteLength) return `lengths differ: ${a.byteLength} vs ${b.byteLength}`;
  for (let i = 0; i < a.byteLength; i++) if (a[i] !== b[i]) return `first difference at byte ${i}: ${a[i]} vs ${b[i]}`;
  return 'identical';
}

/** Deterministic pseudo-random numbers (mulberry32). */
export const rng = mulberry32;
