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
    throw new Error(
      `Could not start the ${what} WebAssembly module (${wasmUrl.pathname.split('/').pop()}): ${(e as Error).message ?? String(e)}`,
    );
  }
}

/** The latest module failures (what went wrong), for tests and the fuzz suite. */
export const wasmFailures: string[] = [];

/**
 * One instance of a module, shared by every file a page or process opens,
 * replaced after it failed: a trap (out-of-bounds access, a bad indirect
 * call), an uncaught C++ exception or an error of the JS glue can leave its
 * heap and the library's state corrupt, so the next file gets a fresh one.
 */
export class WasmSlot<T> {
  private current: Promise<T> | undefined;
  private instance: T | undefined;

  constructor(private readonly create: () => Promise<T>) {}

  get(): Promise<T> {
    this.current ??= this.create().then(
      (m) => (this.instance = m),
      (e: unknown) => {
        this.current = undefined;
        throw e;
      },
    );
    return this.current;
  }

  /** Drops `m` if it is the current instance; the next get() instantiates a new one. */
  discard(m: T, why: string): void {
    wasmFailures.push(why);
    if (wasmFailures.length > 100) wasmFailures.splice(0, 50);
    if (this.instance !== m) return;
    this.instance = undefined;
    this.current = undefined;
  }
}

/**
 * What went wrong inside a module, for a message: a Wasm trap, Emscripten's
 * abort, a C++ exception that escaped (thrown as a number with JS-based
 * exception handling) or an error of the glue.
 */
export function describeWasmFailure(e: unknown): string {
  if (typeof e === 'number') return 'an uncaught C++ exception';
  if (e instanceof Error) return e.message || e.name;
  return String(e);
}

/** Wasm32 pointers above 2 GiB come back as negative numbers. */
export function ptr(p: number): number {
  return p >>> 0;
}

/** The largest block handed to _malloc: the heap is at most 4 GiB, and a file needs room beside it. */
export const MAX_HEAP_BLOCK = 3 * 2 ** 30;

/**
 * Copies `bytes` into a fresh malloc'ed block of the module's heap (the one
 * copy into Wasm memory) and returns the pointer.
 */
export function copyIntoHeap(module: EmscriptenBase, bytes: Uint8Array, what: string): number {
  // _malloc takes a 32-bit size: a larger one would wrap to a small block.
  if (bytes.byteLength > MAX_HEAP_BLOCK)
    throw new Error(
      `${what}: ${formatBytes(bytes.byteLength)} does not fit in WebAssembly memory (at most ${formatBytes(MAX_HEAP_BLOCK)})`,
    );
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
  if (size > MAX_HEAP_BLOCK)
    throw new Error(`${what}: ${formatBytes(size)} does not fit in WebAssembly memory (at most ${formatBytes(MAX_HEAP_BLOCK)})`);
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
