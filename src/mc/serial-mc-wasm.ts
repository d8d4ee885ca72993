// The serial C++ marching cubes (benchmarks/serial-mc/serial_mc.cpp) compiled to
// WebAssembly (wasm/dist/serial_mc.*, made by benchmarks/serial-mc/build.mjs),
// wrapped for TypeScript in Node and in the browser. The volume is copied into the
// Wasm heap once; each run then contours it in place.
import createSerialMc, { type SerialMcModule } from '../../wasm/dist/serial_mc.js';

type Dims3 = readonly [number, number, number];

export interface WasmRun {
  triangleCount: number;
  /** The soup copied out of the Wasm heap, or null when run with copyOut false. */
  positions: Float32Array | null;
}

const wasmUrl = new URL('../../wasm/dist/serial_mc.wasm', import.meta.url);

async function wasmBytes(): Promise<Uint8Array> {
  if (typeof process !== 'undefined' && process.versions?.node) {
    // A specifier the bundler leaves alone: the page never takes this branch.
    const fsPromises = 'node:fs/promises';
    const { readFile } = (await import(/* @vite-ignore */ fsPromises)) as typeof import('node:fs/promises');
    return new Uint8Array(await readFile(wasmUrl));
  }
  const response = await fetch(wasmUrl);
  if (!response.ok) throw new Error(`${wasmUrl}: HTTP ${response.status}`);
  return new Uint8Array(await response.arrayBuffer());
}

export class WasmSerialMc {
  private volumePtr = 0;
  private dims: Dims3 = [0, 0, 0];
  // 8 bytes for the two out-parameters (soup pointer, vertex count).
  private readonly outPtr: number;

  private constructor(private readonly mod: SerialMcModule) {
    this.outPtr = mod._mc_alloc(8);
  }

  static async create(): Promise<WasmSerialMc> {
    return new WasmSerialMc(await createSerialMc({ wasmBinary: await wasmBytes() }));
  }

  /** Copies the volume (x fastest) into the Wasm heap, replacing any previous one. */
  setVolume(values: Float32Array, dims: Dims3): void {
    const [nx, ny, nz] = dims;
    if (values.length !== nx * ny * nz) throw new Error(`volume has ${values.length} values, dims ${dims.join('x')}`);
    this.freeVolume();
    const ptr = this.mod._mc_alloc(values.byteLength);
    if (ptr === 0) throw new Error(`Wasm heap: cannot allocate ${values.byteLength} bytes`);
    this.mod.HEAPF32.set(values, ptr >>> 2);
    this.volumePtr = ptr;
    this.dims = [nx, ny, nz];
  }

  /**
   * Marching cubes of the current volume (same conventions and the same soup as
   * src/mc/serial-mc.ts). copyOut false frees the soup without copying it (timing).
   */
  run(iso: number, { copyOut = true }: { copyOut?: boolean } = {}): WasmRun {
    if (this.volumePtr === 0) throw new Error('WasmSerialMc: setVolume first');
    const m = this.mod;
    const [nx, ny, nz] = this.dims;
    const status = m._mc_marching_cubes(this.volumePtr, nx, ny, nz, iso, this.outPtr, this.outPtr + 4);
    if (status !== 0) throw new Error(`mc_marching_cubes failed (${status === 2 ? 'out of memory' : 'bad input'})`);
    // Views are re-read after the call: growing the heap replaces them.
    const soupPtr = m.HEAPU32[this.outPtr >>> 2];
    const vertexCount = m.HEAPU32[(this.outPtr >>> 2) + 1];
    const positions = copyOut ? m.HEAPF32.slice(soupPtr >>> 2, (soupPtr >>> 2) + vertexCount * 3) : null;
    if (soupPtr !== 0) m._mc_free(soupPtr);
    return { triangleCount: vertexCount / 3, positions };
  }

  /** Frees the volume (the module's memory stays with the instance). */
  dispose(): void {
    this.freeVolume();
  }

  private freeVolume(): void {
    if (this.volumePtr !== 0) this.mod._mc_free(this.volumePtr);
    this.volumePtr = 0;
  }
}
