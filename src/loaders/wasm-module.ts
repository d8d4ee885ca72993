// Instantiates an Emscripten ES module from wasm/dist/ with its .wasm. In the
// page the bundler emits the .wasm as an asset (the `new URL(..., import.meta.url)`
// at the call site) and the glue fetches it; in Node (CLI, tests, benchmarks)
// the URL is a file: URL and we read the bytes ourselves, so the glue needs no
// Node-specific code.

export interface EmscriptenBase {
  HEAPU8: Uint8Array;
  _malloc(size: number): number;
  _free(ptr: number): void;
  UTF8ToString(ptr: number, maxBytesToRead?: number): string;
}

type Factory<T> = (options: {
  wasmBinary?: Uint8Array;
  locateFile?: (path: string, scriptDirectory: string) => string;
  printErr?: (text: string) => void;
}) => Promise<T>;

/** Dynamic import that bundlers leave alone (node:fs is never needed in the page). */
const importNode = (specifier: string): Promise<unknown> => import(/* @vite-ignore */ specifier);

export async function instantiateWasm<T>(factory: Factory<T>, wasmUrl: URL, what: string): Promise<T> {
  try {
    if (wasmUrl.protocol === 'file:') {
      const fs = (await importNode('node:fs/promises')) as typeof import('node:fs/promises');
      const bytes = new Uint8Array(await fs.readFile(wasmUrl));
      return await factory({ wasmBinary: bytes, printErr: () => undefined });
    }
    return await factory({ locateFile: () => wasmUrl.href, printErr: () => undefined });
  } catch (e) {
    throw new Error(`Could not start the ${what} WebAssembly module (${wasmUrl.pathname.split('/').pop()}): ${(e as Error).message ?? String(e)}`);
  }
}

/** Wasm32 pointers above 2 GiB come back as negative numbers. */
export function ptr(p: number): number {
  return p >>> 0;
}

/**
 * Copies `bytes` into a fresh malloc'ed block of the module's heap (the one
 * copy into Wasm memory) and returns the pointer.
 */
export function copyIntoHeap(module: EmscriptenBase, bytes: Uint8Array, what: string): number {
  const p = ptr(module._malloc(Math.max(1, bytes.byteLength)));
  if (p === 0) throw new Error(`${what}: out of WebAssembly memory for ${formatBytes(bytes.byteLength)}`);
  module.HEAPU8.set(bytes, p);
  return p;
}

/**
 * Streams a Blob (a dropped File) into a fresh malloc'ed block of the heap,
 * chunk by chunk, so the file's bytes exist once, in Wasm memory, instead of
 * once in an ArrayBuffer and again in the heap. Frees the block on failure.
 */
export async function streamIntoHeap(
  module: EmscriptenBase,
  blob: Blob,
  what: string,
  onProgress?: (done: number, total: number) => void,
): Promise<number> {
  const size = blob.size;
  const p = ptr(module._malloc(Math.max(1, size)));
  if (p === 0) throw new Error(`${what}: out of WebAssembly memory for ${formatBytes(size)}`);
  try {
    let at = 0;
    const reader = blob.stream().getReader();
    for (;;) {
      const { done, value } = await reader.read();
      if (done) break;
      if (at + value.byteLength > size) throw new Error(`${what}: the file grew while it was read`);
      // The heap may grow between reads (another module call): take a fresh view each time.
      module.HEAPU8.set(value, p + at);
      at += value.byteLength;
      onProgress?.(at, size);
    }
    if (at !== size) throw new Error(`${what}: read ${at} of ${size} bytes`);
    return p;
  } catch (e) {
    module._free(p);
    throw e;
  }
}

export function formatBytes(n: number): string {
  if (n < 1024) return `${n} B`;
  if (n < 1024 ** 2) return `${(n / 1024).toFixed(1)} KiB`;
  if (n < 1024 ** 3) return `${(n / 1024 ** 2).toFixed(1)} MiB`;
  return `${(n / 1024 ** 3).toFixed(2)} GiB`;
}
