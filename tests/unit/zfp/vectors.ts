// The shared zfp test vectors (made by zfp 1.0.1 itself): see ../shared/data/README.md.
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { sharedData } from '../../helpers/python.ts';

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
export function rng(seed: number): () => number {
  let s = seed >>> 0;
  return () => {
    s = (s + 0x6d2b79f5) >>> 0;
    let t = s;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}
