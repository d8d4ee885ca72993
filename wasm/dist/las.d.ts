// Types of wasm/dist/las.js (LASzip reader + wasm/las/las_api.cpp), hand-written.
export interface EmscriptenModuleOptions {
  /** The .wasm bytes (Node: read from disk). */
  wasmBinary?: ArrayBuffer | Uint8Array;
  /** Where the .wasm is served (page: the bundler's asset URL). */
  locateFile?: (path: string, scriptDirectory: string) => string;
  print?: (text: string) => void;
  printErr?: (text: string) => void;
}

export interface EmscriptenModule {
  HEAPU8: Uint8Array;
  HEAPU16: Uint16Array;
  HEAP32: Int32Array;
  HEAPF32: Float32Array;
  HEAPF64: Float64Array;
  _malloc(size: number): number;
  _free(ptr: number): void;
  UTF8ToString(ptr: number, maxBytesToRead?: number): string;
}

export interface LasWasm extends EmscriptenModule {
  _las_open(data: number, size: number): number;
  _las_error(reader: number): number;
  _las_info(reader: number, out: number): number;
  _las_header_string(reader: number, which: number): number;
  _las_read(reader: number, n: number, positions: number, rgb: number, intensity: number, classification: number, xyz: number, records: number): number;
  /** Points read so far outside the header's bounds; -1 when the bounds are not finite. */
  _las_outside(reader: number): number;
  _las_close(reader: number): void;
}

export default function createLasModule(options?: EmscriptenModuleOptions): Promise<LasWasm>;
