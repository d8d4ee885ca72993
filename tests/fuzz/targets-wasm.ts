// Fuzz targets of the Wasm readers (LAS/LAZ, TIFF): provided by the Wasm half
// of issue 13; empty until that lands.
import type { FuzzTarget } from './target.ts';

export const wasmFuzzTargets: FuzzTarget[] = [];
