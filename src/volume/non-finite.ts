// NaN and Inf in float volumes. zfp cannot carry them (its block transform
// mixes every value of a block, so one NaN or Inf spoils the whole block),
// so they are replaced before the GPU compresses a volume, and the user is
// told how many there were and what became of them:
//   NaN, -Inf -> the smallest finite value: outside every surface (a cell is
//                inside when value >= isovalue, and surfaces exist only for
//                isovalues above the minimum);
//   +Inf      -> the largest finite value.
// float64 values beyond float32's range (which the float32 conversion would
// turn into +-Inf) count as infinite. The value range, the block profile and
// the isovalue choice therefore see only the finite values.

import type { DType } from '../core/dtype.ts';

const FLT_MAX = 3.4028234663852886e38;

export interface NonFiniteCount {
  values: number;
  nan: number;
  posInf: number;
  negInf: number;
  /** Range of the finite values (Infinity, -Infinity when there are none). */
  finiteMin: number;
  finiteMax: number;
}

function floatView(data: Uint8Array, dtype: 'float32' | 'float64'): Float32Array | Float64Array {
  const width = dtype === 'float32' ? 4 : 8;
  const aligned = data.byteOffset % width === 0 ? data : data.slice();
  const n = Math.floor(aligned.byteLength / width);
  return dtype === 'float32'
    ? new Float32Array(aligned.buffer, aligned.byteOffset, n)
    : new Float64Array(aligned.buffer, aligned.byteOffset, n);
}

/** Counts NaN and infinite samples; undefined for integer types (always finite). */
export function countNonFinite(data: Uint8Array, dtype: DType): NonFiniteCount | undefined {
  if (dtype !== 'float32' && dtype !== 'float64') return undefined;
  const v = floatView(data, dtype);
  let nan = 0,
    posInf = 0,
    negInf = 0;
  let lo = Infinity,
    hi = -Infinity;
  for (let i = 0; i < v.length; i++) {
    const x = v[i];
    if (x !== x) nan++;
    else if (x > FLT_MAX) posInf++;
    else if (x < -FLT_MAX) negInf++;
    else {
      if (x < lo) lo = x;
      if (x > hi) hi = x;
    }
  }
  return { values: v.length, nan, posInf, negInf, finiteMin: lo, finiteMax: hi };
}

export function nonFiniteTotal(c: NonFiniteCount): number {
  return c.nan + c.posInf + c.negInf;
}

/** A copy of `data` with NaN/-Inf set to the finite minimum and +Inf to the finite maximum. */
export function replaceNonFinite(data: Uint8Array, dtype: 'float32' | 'float64', c: NonFiniteCount): Uint8Array {
  const out = data.slice();
  const v = floatView(out, dtype);
  for (let i = 0; i < v.length; i++) {
    const x = v[i];
    if (x !== x || x < -FLT_MAX) v[i] = c.finiteMin;
    else if (x > FLT_MAX) v[i] = c.finiteMax;
  }
  return out;
}

function parts(c: NonFiniteCount): string {
  const p: string[] = [];
  if (c.nan) p.push(`${c.nan} NaN`);
  if (c.posInf) p.push(`${c.posInf} +Inf`);
  if (c.negInf) p.push(`${c.negInf} -Inf`);
  return p.join(', ');
}

/** The notice shown by the page and printed by the CLI. */
export function nonFiniteNotice(c: NonFiniteCount): string {
  const became: string[] = [];
  if (c.nan || c.negInf)
    became.push(
      `${[c.nan ? 'NaN' : '', c.negInf ? '-Inf' : ''].filter(Boolean).join(' and ')} became the smallest finite value (${c.finiteMin}, outside every surface)`,
    );
  if (c.posInf) became.push(`+Inf became the largest (${c.finiteMax})`);
  return `${nonFiniteTotal(c)} of ${c.values} values are not finite (${parts(c)}); zfp cannot store NaN or Inf, so before compressing ${became.join(' and ')}`;
}

/** Why a volume without any finite value cannot be used. */
export function allNonFiniteMessage(c: NonFiniteCount): string {
  return `all ${c.values} values are NaN or infinite (${parts(c)}): there is no value range and no surface to draw`;
}
