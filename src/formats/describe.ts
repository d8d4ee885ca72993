// A summary of a file as far as our parsers can tell from its name, size and
// first bytes: what `cli info` prints and the page shows before loading.

import { DTYPE_BYTES } from '../volume/dtype.ts';
import type { Dims } from '../volume/naming.ts';
import { describeMode, parseZfpHeader, ZfpFormatError } from '../zfp/header.ts';
import { detectFile, type FileKind } from './detect.ts';

export interface FileDescription {
  kind: FileKind;
  detectedBy: string;
  bytes: number;
  dims?: Dims;
  dtype?: string;
  /** zfp only */
  zfpHeader?: boolean;
  zfpMode?: string;
  rate?: number;
  bitsPerBlock?: number;
  blocks?: number;
  /** Problems found (e.g. size does not match the shape). */
  problems: string[];
}

function blockCount(d: Dims): number {
  return Math.ceil(d[0] / 4) * Math.ceil(d[1] / 4) * Math.ceil(d[2] / 4);
}

export function describeFile(fileName: string, bytes: number, head: Uint8Array, opts: { rate?: number } = {}): FileDescription {
  const detected = detectFile(fileName, head);
  const out: FileDescription = { kind: detected.kind, detectedBy: detected.why, bytes, problems: [] };
  const name = detected.name;
  switch (detected.kind) {
    case 'zfp': {
      out.zfpHeader = true;
      try {
        const h = parseZfpHeader(head);
        out.dtype = h.scalarType;
        out.zfpMode = describeMode(h.mode, h.dimensionality);
        if (h.dimensionality !== 3) out.problems.push(`the field is ${h.dimensionality}D; only 3D volumes are supported`);
        out.dims = [h.size[0], h.size[1], h.size[2]];
        if (h.mode.kind === 'fixed-rate' && h.mode.maxBits) {
          out.bitsPerBlock = h.mode.maxBits;
          out.rate = h.mode.maxBits / 4 ** h.dimensionality;
          if (h.dimensionality === 3) {
            out.blocks = blockCount(out.dims);
            const needBits = h.headerBits + out.blocks * out.bitsPerBlock;
            if (bytes * 8 < needBits) out.problems.push(`truncated: the header promises ${Math.ceil(needBits / 8)} bytes, the file has ${bytes}`);
          }
        } else {
          out.problems.push(`not fixed-rate (${out.zfpMode}); only fixed-rate streams can be decoded block by block`);
        }
      } catch (e) {
        if (!(e instanceof ZfpFormatError)) throw e;
        out.problems.push(e.message);
      }
      break;
    }
    case 'zfp-headerless': {
      out.zfpHeader = false;
      out.dims = name.dims;
      out.dtype = name.dtype;
      out.rate = opts.rate ?? name.rate;
      if (!name.dims) out.problems.push('the name carries no shape (expected name_XxYxZ_float32...zfp)');
      if (out.rate === undefined) out.problems.push('the rate is unknown: give --rate or name the file ...crateR.zfp');
      if (name.dims && out.rate !== undefined) {
        out.blocks = blockCount(name.dims);
        out.bitsPerBlock = Math.round(64 * out.rate);
        const expect = Math.ceil((out.blocks * out.bitsPerBlock) / 64) * 8;
        if (bytes !== expect) {
          out.problems.push(`a fixed-rate ${out.rate} stream of this shape is ${expect} bytes, the file has ${bytes} (not fixed-rate, or a different shape or rate)`);
        }
      }
      break;
    }
    case 'raw': {
      out.dims = name.dims;
      out.dtype = name.dtype;
      if (!name.dims || !name.dtype) out.problems.push('the name carries no shape and type (expected name_XxYxZ_dtype.raw)');
      else {
        const expect = name.dims[0] * name.dims[1] * name.dims[2] * DTYPE_BYTES[name.dtype];
        if (expect !== bytes) out.problems.push(`${name.dims.join('x')} ${name.dtype} is ${expect} bytes, the file has ${bytes}`);
      }
      break;
    }
    default:
      break;
  }
  return out;
}
