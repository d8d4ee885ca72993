// What a file name says about a volume: `name_XxYxZ_dtype.raw`, and the
// header-less zfp convention `name_XxYxZ_float32.raw.crate4.zfp` (or
// `name_XxYxZ_float32.zfp`, whose rate must be given separately).

import { isDType, type DType } from './dtype.ts';

export type Dims = [number, number, number];

export interface NameInfo {
  /** The part before `_XxYxZ`. */
  base: string;
  dims?: Dims;
  dtype?: DType;
  /** From `.crateR.` or `.rateR.` in the name. */
  rate?: number;
}

const SHAPE = /_(\d+)x(\d+)x(\d+)(?:_([a-z]+\d*))?/i;
const RATE = /\.c?rate(\d+(?:\.\d+)?)(?=\.|$)/i;

export function parseVolumeName(fileName: string): NameInfo {
  const name = fileName.split(/[\\/]/).pop() ?? fileName;
  const info: NameInfo = { base: name.replace(/\..*$/, '') };
  const m = SHAPE.exec(name);
  if (m) {
    info.base = name.slice(0, m.index);
    info.dims = [Number(m[1]), Number(m[2]), Number(m[3])];
    const t = m[4]?.toLowerCase();
    if (t && isDType(t)) info.dtype = t;
  }
  const r = RATE.exec(name);
  if (r) info.rate = Number(r[1]);
  return info;
}

export function formatDims(d: Dims): string {
  return `${d[0]}x${d[1]}x${d[2]}`;
}
