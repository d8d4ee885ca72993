// Types of wasm/dist/tiff.js (libtiff + zlib + libjpeg-turbo + wasm/tiff/tiff_api.c), hand-written.
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

export interface TiffWasm extends EmscriptenModule {
  _tiff_open(data: number, size: number): number;
  _tiff_error(file: number): number;
  _tiff_page_count(file: number): number;
  _tiff_page_info(file: number, page: number, out: number): number;
  _tiff_page_description(file: number, page: number): number;
  _tiff_page_bytes(file: number, page: number): number;
  _tiff_read_page(file: number, page: number, out: number, outSize: number): number;
  _tiff_close(file: number): void;
}

export default function createTiffModule(options?: EmscriptenModuleOptions): Promise<TiffWasm>;
