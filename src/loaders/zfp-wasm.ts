// zfp's own serial C decoder (zfp 1.0.1) compiled to WebAssembly
// (wasm/zfp/zfp_api.c + wasm/dist/zfp.{js,wasm}, built by `npm run build:wasm`),
// for Node and the browser: the "zfp's C decoder in Wasm" column of the paper's
// ZFP table. The stream is copied into the Wasm heap once (`load`); each
// `decode()` then runs zfp_decompress on it into an output array that also
// lives in the heap, so a timed decode is zfp's work alone.
import createZfpModule, { type ZfpWasm } from '../../wasm/dist/zfp.js';
import { copyIntoHeap, instantiateWasm, ptr } from './wasm-module.ts';

let module: Promise<ZfpWasm> | undefined;

export function loadZfpWasm(): Promise<ZfpWasm> {
  module ??= instantiateWasm(createZfpModule, new URL('../../wasm/dist/zfp.wasm', import.meta.url), 'zfp').catch((e: unknown) => {
    module = undefined;
    throw e;
  });
  return module;
}

export interface ZfpWasmInfo {
  dims: [number, number, number];
  /** zfp_type: 3 = float32. */
  type: number;
  dimensionality: number;
  /** zfp_mode: 2 = fixed rate. */
  mode: number;
  bitsPerBlock: number;
  headerBits: number;
}

export class ZfpWasmError extends Error {
  constructor(message: string) {
    super(message);
    this.name = 'ZfpWasmError';
  }
}

/** A zfp stream with zfp's header, loaded into the Wasm heap with room for its decoded field. */
export class ZfpWasmStream {
  private inPtr = 0;
  private outPtr = 0;
  readonly count: number;

  private constructor(
    private readonly m: ZfpWasm,
    private readonly size: number,
    readonly info: ZfpWasmInfo,
    inPtr: number,
  ) {
    this.inPtr = inPtr;
    const [nx, ny, nz] = info.dims;
    this.count = nx * ny * nz;
    this.outPtr = ptr(m._malloc(Math.max(4, this.count * 4)));
    if (this.outPtr === 0) {
      m._free(inPtr);
      this.inPtr = 0;
      throw new ZfpWasmError(`out of WebAssembly memory for ${this.count * 4} bytes of output`);
    }
  }

  /** Copies `bytes` (a fixed-rate float32 3D stream with zfp's header) into the heap and reads its header. */
  static async load(bytes: Uint8Array, name = 'stream'): Promise<ZfpWasmStream> {
    const m = await loadZfpWasm();
    const inPtr = copyIntoHeap(m, bytes, name);
    const infoPtr = ptr(m._malloc(32));
    try {
      const status = m._zfp_api_info(inPtr, bytes.byteLength, infoPtr);
      if (status !== 0) throw new ZfpWasmError(`${name}: ${m.UTF8ToString(m._zfp_api_error())}`);
      const w = m.HEAPU32.subarray(infoPtr >>> 2, (infoPtr >>> 2) + 8);
      const info: ZfpWasmInfo = {
        dims: [w[0], w[1], w[2]],
        type: w[3],
        dimensionality: w[4],
        mode: w[5],
        bitsPerBlock: w[6],
        headerBits: w[7],
      };
      return new ZfpWasmStream(m, bytes.byteLength, info, inPtr);
    } catch (e) {
      m._free(inPtr);
      throw e;
    } finally {
      m._free(infoPtr);
    }
  }

  /** Decodes the whole field into the heap (zfp_decompress); view it with `output()`. */
  decode(): void {
    if (this.inPtr === 0) throw new ZfpWasmError('stream was freed');
    const status = this.m._zfp_api_decode(this.inPtr, this.size, this.outPtr, this.count);
    if (status !== 0) throw new ZfpWasmError(this.m.UTF8ToString(this.m._zfp_api_error()));
  }

  /** The decoded field (x fastest): a view of the heap, valid until the next call into the module. */
  output(): Float32Array {
    return this.m.HEAPF32.subarray(this.outPtr >>> 2, (this.outPtr >>> 2) + this.count);
  }

  free(): void {
    if (this.inPtr !== 0) this.m._free(this.inPtr);
    if (this.outPtr !== 0) this.m._free(this.outPtr);
    this.inPtr = 0;
    this.outPtr = 0;
  }
}

/** Decodes a fixed-rate float32 3D stream with zfp's header into a new Float32Array. */
export async function decodeZfpWasm(bytes: Uint8Array, name?: string): Promise<Float32Array> {
  const s = await ZfpWasmStream.load(bytes, name);
  try {
    s.decode();
    return s.output().slice();
  } finally {
    s.free();
  }
}

/** Decodes a header-less fixed-rate stream of an nx*ny*nz float32 field at `rate` bits per value. */
export async function decodeZfpWasmRaw(bytes: Uint8Array, dims: [number, number, number], rate: number): Promise<Float32Array> {
  const m = await loadZfpWasm();
  const [nx, ny, nz] = dims;
  const count = nx * ny * nz;
  const inPtr = copyIntoHeap(m, bytes, 'stream');
  const outPtr = ptr(m._malloc(Math.max(4, count * 4)));
  try {
    if (outPtr === 0) throw new ZfpWasmError(`out of WebAssembly memory for ${count * 4} bytes of output`);
    const status = m._zfp_api_decode_raw(inPtr, bytes.byteLength, nx, ny, nz, rate, outPtr, count);
    if (status !== 0) throw new ZfpWasmError(m.UTF8ToString(m._zfp_api_error()));
    return m.HEAPF32.slice(outPtr >>> 2, (outPtr >>> 2) + count);
  } finally {
    m._free(inPtr);
    if (outPtr !== 0) m._free(outPtr);
  }
}
