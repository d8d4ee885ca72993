/** Writes bench:gpu as one JavaScript file to `outfile` (bundle.mjs); resolves with esbuild's warnings. */
export function bundleBenchGpu(outfile: string): Promise<unknown[]>;
