// Types of wasm/dist/zfp.js (LLNL zfp 1.0.1 + wasm/zfp/zfp_api.c), hand-written.
import type { EmscriptenModule, EmscriptenModuleOptions } from './las.js';

export interface ZfpWasm extends EmscriptenModule {
  HEAPU32: Uint32Array;
  /** Header facts into out[0..7]: nx, ny, nz, zfp_type, dims, zfp_mode, maxbits, header bits. 0 = ok. */
  _zfp_api_info(data: number, size: number, out: number): number;
  /** A fixed-rate 3D float32 stream with zfp's header -> out (count floats). 0 = ok. */
  _zfp_api_decode(data: number, size: number, out: number, count: number): number;
  /** A header-less fixed-rate stream of nx*ny*nz float32 at `rate` bits per value -> out. 0 = ok. */
  _zfp_api_decode_raw(data: number, size: number, nx: number, ny: number, nz: number, rate: number, out: number, count: number): number;
  /** The message of the last failure (a C string). */
  _zfp_api_error(): number;
}

export default function createZfpModule(options?: EmscriptenModuleOptions): Promise<ZfpWasm>;
