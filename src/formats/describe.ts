// A summary of a file as far as our parsers can tell from its name, size and
// first bytes: what `cli info` prints and the page shows before loading.

import { DTYPE_BYTES } from '../core/dtype.ts';
import type { Dims } from '../core/naming.ts';
import { describeZfpStream } from '../zfp/format.ts';
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
  blockGrid?: Dims;
  /** Bit where block 0 starts (the header's length; 0 without header). */
  payloadBitOffset?: number;
  /** Size of the volume decoded to float32. */
  decodedBytes?: number;
  /** Problems found (e.g. size does not match the shape). */
  problems: string[];
}

export function describeFile(fileName: string, bytes: number, head: Uint8Array, opts: { rate?: number } = {}): FileDescription {
  const detected = detectFile(fileName, head);
  const out: FileDescription = { kind: detected.kind, detectedBy: detected.why, bytes, problems: [] };
  const name = detected.name;
  switch (detected.kind) {
    case 'zfp':
    case 'zfp-headerless': {
      out.zfpHeader = detected.kind === 'zfp';
      // What can be said even when the stream is unusable.
      if (detected.kind === 'zfp') {
        try {
          const h = parseZfpHeader(head);
          out.dtype = h.scalarType;
          out.zfpMode = describeMode(h.mode, h.dimensionality);
          out.dims = [h.size[0], h.size[1], h.size[2]];
          if (h.dimensionality !== 3) out.dims = undefined;
        } catch (e) {
          if (!(e instanceof ZfpFormatError)) throw e;
        }
      } else {
        out.dims = name.dims;
        out.dtype = name.dtype;
        out.rate = opts.rate ?? name.rate;
      }
      try {
        const info = describeZfpStream(fileName, bytes, head, opts);
        out.dims = info.dims;
        out.dtype = info.scalarType;
        out.zfpMode = info.mode;
        out.rate = info.rate;
        out.bitsPerBlock = info.bitsPerBlock;
        out.blocks = info.blockCount;
        out.blockGrid = info.blockGrid;
        out.payloadBitOffset = info.payloadBitOffset;
        out.decodedBytes = info.dims[0] * info.dims[1] * info.dims[2] * 4;
        out.problems.push(...info.notes);
      } catch (e) {
        if (!(e instanceof ZfpFormatError)) throw e;
        out.problems.push(e.message);
      }
      break;
    }
    case 'raw': {
      out.dims = name.dims;
      out.dtype = name.dtype;
      if (!name.dims || !name.dtype) out.problems.push('the name carries no shape and type (expected name_XxYxZ_dtype.raw)');
      else if (name.dims.some((n) => !Number.isSafeInteger(n) || n < 1)) {
        out.problems.push(`the shape ${name.dims.join('x')} in the name is impossible: every dimension must be a whole number from 1 up`);
      } else {
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
