// Seeded mutations of valid files: what a stranger's file may look like.
// Every case is reproducible from (reader, seed index, case number, run seed):
// the generator is mulberry32 (src/util/random.ts), so a failing case can be
// re-made exactly from the report.
//
// Classes (as in issue 13): truncations, bit flips, header fields set to
// extremes (binary words and numbers in text headers), lying names (huge or
// zero dims, `.crate0`, other types and extensions), appended garbage, gzip
// bombs and damaged gzip (NRRD), NaN/Inf volumes (float raw and NRRD).

import { gzipSync } from 'node:zlib';
import { mulberry32 } from '../../src/util/random.ts';
import { parseNrrdHeader } from '../../src/volume/nrrd.ts';
import type { FuzzSeed } from './target.ts';

export interface FuzzCase {
  name: string;
  bytes: Uint8Array;
  /** What was done, e.g. "truncate to 37" or "name fuel_0x64x64_float32.raw". */
  mutation: string;
}

export type Rng = () => number;

const int = (rng: Rng, n: number) => Math.floor(rng() * n);
const pick = <T>(rng: Rng, a: readonly T[]): T => a[int(rng, a.length)];

/** Offsets in the first bytes are likelier: that is where headers are. */
function offset(rng: Rng, length: number): number {
  if (length === 0) return 0;
  return rng() < 0.7 ? int(rng, Math.min(length, 256)) : int(rng, length);
}

const EXTREME_U32 = [0, 1, 2, 0x7f, 0x80, 0xff, 0x7fff, 0x8000, 0xffff, 0x10000, 0x7fffffff, 0x80000000, 0xfffffffe, 0xffffffff];
const EXTREME_TEXT = [
  '0',
  '-1',
  '1',
  '-2147483648',
  '2147483647',
  '4294967295',
  '4294967296',
  '99999999999999999999',
  '1e308',
  '-1e308',
  '1e-320',
  'nan',
  'NaN',
  'inf',
  '-inf',
  '65537',
  '0.5',
  '',
  '18446744073709551616',
];

function truncate(c: FuzzCase, rng: Rng): FuzzCase {
  const n = c.bytes.length;
  const to = rng() < 0.5 ? int(rng, Math.min(n, 300)) : int(rng, n);
  return { ...c, bytes: c.bytes.slice(0, to), mutation: `truncate to ${to}` };
}

function bitFlips(c: FuzzCase, rng: Rng): FuzzCase {
  const bytes = c.bytes.slice();
  const count = 1 + int(rng, 16);
  const at: number[] = [];
  for (let i = 0; i < count && bytes.length > 0; i++) {
    const o = offset(rng, bytes.length);
    bytes[o] ^= 1 << int(rng, 8);
    at.push(o);
  }
  return { ...c, bytes, mutation: `flip ${count} bits at ${at.slice(0, 6).join(',')}${at.length > 6 ? ',…' : ''}` };
}

function binaryField(c: FuzzCase, rng: Rng): FuzzCase {
  const bytes = c.bytes.slice();
  if (bytes.length < 4) return bitFlips(c, rng);
  const width = pick(rng, [1, 2, 4, 8]);
  const o = Math.min(bytes.length - width, offset(rng, bytes.length)) & ~(width === 1 ? 0 : width - 1);
  const v = pick(rng, EXTREME_U32);
  const view = new DataView(bytes.buffer);
  if (width === 1) view.setUint8(o, v & 0xff);
  else if (width === 2) view.setUint16(o, v & 0xffff, true);
  else if (width === 4) view.setUint32(o, v >>> 0, true);
  else {
    view.setUint32(o, v >>> 0, true);
    view.setUint32(o + 4, rng() < 0.5 ? 0 : 0xffffffff, true);
  }
  return { ...c, bytes, mutation: `set ${width}-byte field at ${o} to 0x${v.toString(16)}` };
}

/** Numbers in a text header (NRRD fields, SWC columns) replaced by extremes; lines dropped or repeated. */
function textField(c: FuzzCase, rng: Rng): FuzzCase {
  const limit = Math.min(c.bytes.length, 8192);
  const head = new TextDecoder('latin1').decode(c.bytes.subarray(0, limit));
  const numbers = [...head.matchAll(/-?\d+(?:\.\d+)?(?:e[-+]?\d+)?/gi)];
  if (numbers.length === 0 || rng() < 0.15) {
    // drop or repeat a line
    const lines = head.split('\n');
    const i = int(rng, lines.length);
    const drop = rng() < 0.5;
    if (drop) lines.splice(i, 1);
    else lines.splice(i, 0, lines[i]);
    const text = new TextEncoder().encode(lines.join('\n'));
    const bytes = new Uint8Array(text.length + c.bytes.length - limit);
    bytes.set(text);
    bytes.set(c.bytes.subarray(limit), text.length);
    return { ...c, bytes, mutation: `${drop ? 'drop' : 'repeat'} line ${i + 1}` };
  }
  const m = pick(rng, numbers);
  const value = pick(rng, EXTREME_TEXT);
  const start = m.index!;
  const text = new TextEncoder().encode(head.slice(0, start) + value + head.slice(start + m[0].length));
  const bytes = new Uint8Array(text.length + c.bytes.length - limit);
  bytes.set(text);
  bytes.set(c.bytes.subarray(limit), text.length);
  return { ...c, bytes, mutation: `number "${m[0]}" at ${start} -> "${value}"` };
}

const LYING_DIMS = [
  '0x64x64',
  '1x1x1',
  '65537x65537x65537',
  '4294967296x1x1',
  '99999999999999999999x2x2',
  '2097152x2097152x1',
  '100000x100000x100000',
  '3x5x7',
  '64x64x65',
];

/** The name says something the file is not. */
function lyingName(c: FuzzCase, rng: Rng): FuzzCase {
  const dot = c.name.indexOf('.');
  const stem = dot < 0 ? c.name : c.name.slice(0, dot);
  const ext = dot < 0 ? '' : c.name.slice(dot);
  const base = stem.replace(/_\d+x\d+x\d+(_[a-z]+\d*)?$/i, '');
  const dtype = /_(u?int(?:8|16)|float(?:32|64))/i.exec(stem)?.[1] ?? 'float32';
  const kind = int(rng, 5);
  let name: string;
  if (kind === 0) name = `${base}_${pick(rng, LYING_DIMS)}_${dtype}${ext}`;
  else if (kind === 1)
    name = `${base}_${/_\d+x\d+x\d+/.exec(stem)?.[0].slice(1) ?? '16x16x16'}_float32.raw.${pick(rng, ['crate0', 'crate0.0', 'crate99999999', 'crate0.001', 'rate0', 'crate1e9', 'crate33000', 'crate8'])}.zfp`;
  else if (kind === 2)
    name = `${stem.replace(/_(u?int(?:8|16)|float(?:32|64))/i, `_${pick(rng, ['uint8', 'int16', 'float64', 'float8', 'int32', 'bogus'])}`)}${ext}`;
  else if (kind === 3) name = `${stem}${pick(rng, ['.raw', '.zfp', '.nrrd', '.swc', '.tif', '.laz', '', '.RAW', '.raw.crate0.zfp'])}`;
  else name = `${base}_${pick(rng, LYING_DIMS)}_${dtype}.raw.${pick(rng, ['crate0', 'crate4', 'crate0.01'])}.zfp`;
  return { ...c, name, mutation: `name ${name}` };
}

function appendGarbage(c: FuzzCase, rng: Rng): FuzzCase {
  const extra = 1 + int(rng, 4096);
  const bytes = new Uint8Array(c.bytes.length + extra);
  bytes.set(c.bytes);
  for (let i = c.bytes.length; i < bytes.length; i++) bytes[i] = int(rng, 256);
  return { ...c, bytes, mutation: `append ${extra} random bytes` };
}

// ---- NRRD: gzip payloads

let bombCache: Uint8Array | undefined;
/** gzip of 1 GiB of zeros (about 1 MB), made once per process by streaming deflate. */
export function gzipBomb(): Uint8Array {
  if (!bombCache) {
    // deflate of 1 GiB of zeros: made from 64 MiB (a gzip member each) repeated: a gzip
    // file may hold several members, and readers inflate them all.
    const member = gzipSync(new Uint8Array(64 << 20), { level: 9 });
    bombCache = new Uint8Array(member.length * 16);
    for (let i = 0; i < 16; i++) bombCache.set(member, i * member.length);
  }
  return bombCache;
}

function nrrdHeader(c: FuzzCase): { text: string; dataOffset: number } | undefined {
  try {
    const { dataOffset } = parseNrrdHeader(c.bytes);
    return { text: new TextDecoder().decode(c.bytes.subarray(0, dataOffset)), dataOffset };
  } catch {
    return undefined;
  }
}

function withHeader(text: string, payload: Uint8Array): Uint8Array {
  const head = new TextEncoder().encode(text);
  const out = new Uint8Array(head.length + payload.length);
  out.set(head);
  out.set(payload, head.length);
  return out;
}

/** NRRD with a gzip bomb, damaged gzip, or gzip of the right data cut short. */
function gzipPayload(c: FuzzCase, rng: Rng): FuzzCase {
  const h = nrrdHeader(c);
  if (!h) return bitFlips(c, rng);
  const gzText = h.text.replace(/encoding:\s*\w+/i, 'encoding: gzip');
  const kind = int(rng, 5);
  const data = c.bytes.subarray(h.dataOffset);
  const isGzip = /encoding:\s*(gzip|gz)\b/i.test(h.text);
  const plain = isGzip ? new Uint8Array(0) : data;
  if (kind === 0) return { ...c, bytes: withHeader(gzText, gzipBomb()), mutation: 'gzip bomb (1 GiB of zeros) as payload' };
  if (kind === 1) {
    const gz = gzipSync(plain.length > 0 ? plain : data);
    const cut = int(rng, gz.length);
    return { ...c, bytes: withHeader(gzText, gz.subarray(0, cut)), mutation: `gzip payload cut at ${cut} of ${gz.length}` };
  }
  if (kind === 2) {
    const gz = Uint8Array.from(gzipSync(plain.length > 0 ? plain : data));
    for (let i = 0; i < 1 + int(rng, 8); i++) gz[int(rng, gz.length)] ^= 1 << int(rng, 8);
    return { ...c, bytes: withHeader(gzText, gz), mutation: 'gzip payload with flipped bits' };
  }
  if (kind === 3) return { ...c, bytes: withHeader(gzText, data.slice(0, 64)), mutation: 'encoding gzip, payload not gzip' };
  // a small header size with a payload far larger than announced
  const small = gzText.replace(/sizes:\s*([^\n]*)/i, () => 'sizes: 2 2 2');
  return { ...c, bytes: withHeader(small, gzipBomb()), mutation: 'sizes 2 2 2 over a gzip bomb' };
}

// ---- NaN / Inf samples

/** Where the float samples of a seed are (float raw by name, NRRD float with raw encoding). */
function floatSamples(c: FuzzCase): { offset: number; count: number; width: 4 | 8; big: boolean } | undefined {
  const nameType = /_(float32|float64)\.raw$/i.exec(c.name)?.[1];
  if (nameType) {
    const width = nameType === 'float32' ? 4 : 8;
    return { offset: 0, count: Math.floor(c.bytes.length / width), width, big: false };
  }
  const h = nrrdHeader(c);
  if (!h) return undefined;
  const type = /\ntype:\s*(float|double)\s*\n/i.exec(h.text)?.[1]?.toLowerCase();
  if (!type || !/encoding:\s*raw/i.test(h.text)) return undefined;
  const width = type === 'float' ? 4 : 8;
  return { offset: h.dataOffset, count: Math.floor((c.bytes.length - h.dataOffset) / width), width, big: /endian:\s*big/i.test(h.text) };
}

function nonFinite(c: FuzzCase, rng: Rng): FuzzCase {
  const s = floatSamples(c);
  if (!s || s.count === 0) return bitFlips(c, rng);
  const bytes = c.bytes.slice();
  const view = new DataView(bytes.buffer, s.offset, s.count * s.width);
  const values = [NaN, Infinity, -Infinity];
  const mode = int(rng, 4);
  const set = (i: number, v: number) => (s.width === 4 ? view.setFloat32(i * 4, v, !s.big) : view.setFloat64(i * 8, v, !s.big));
  let what: string;
  if (mode === 0) {
    const v = pick(rng, values);
    for (let i = 0; i < s.count; i++) set(i, v);
    what = `all ${s.count} samples ${v}`;
  } else if (mode === 1) {
    for (let i = 0; i < s.count; i++) set(i, pick(rng, values));
    what = 'all samples NaN/+Inf/-Inf';
  } else {
    const n = mode === 2 ? 1 + int(rng, 8) : Math.max(1, Math.floor(s.count * rng() * 0.5));
    for (let i = 0; i < n; i++) set(int(rng, s.count), pick(rng, values));
    what = `${n} samples NaN/±Inf`;
  }
  return { ...c, bytes, mutation: what };
}

export type Mutator = (c: FuzzCase, rng: Rng) => FuzzCase;

/** Mutators and their weights; NRRD- and float-specific ones fall back to bit flips elsewhere. */
const MUTATORS: [Mutator, number][] = [
  [truncate, 3],
  [bitFlips, 4],
  [binaryField, 3],
  [textField, 3],
  [lyingName, 2],
  [appendGarbage, 1],
  [gzipPayload, 1],
  [nonFinite, 2],
];

/**
 * Case `index` of the mutated files made from `seeds` (a seed is picked,
 * then 1 to 3 mutations are applied in a row).
 */
export function makeCase(seeds: readonly FuzzSeed[], index: number, runSeed: number, reader: string): FuzzCase & { seed: string } {
  let h = runSeed >>> 0;
  for (const ch of reader) h = Math.imul(h ^ ch.charCodeAt(0), 0x01000193) >>> 0;
  const rng = mulberry32((h ^ Math.imul(index + 1, 0x9e3779b1)) >>> 0);
  const seed = seeds[int(rng, seeds.length)];
  let c: FuzzCase = { name: seed.name, bytes: seed.bytes, mutation: '' };
  const steps = 1 + (rng() < 0.3 ? int(rng, 3) : 0);
  const done: string[] = [];
  const total = MUTATORS.reduce((s, [, w]) => s + w, 0);
  for (let i = 0; i < steps; i++) {
    let r = rng() * total;
    let m = MUTATORS[0][0];
    for (const [f, w] of MUTATORS) {
      if ((r -= w) < 0) {
        m = f;
        break;
      }
    }
    c = m(c, rng);
    done.push(c.mutation);
  }
  return { ...c, mutation: done.join('; '), seed: seed.name };
}
