// bench:gpu as one JavaScript file (esbuild): the benchmark and the product
// code it drives, WGSL inlined (the `?raw` imports Vite and the Node loaders
// give), so a machine with only a Node binary runs it. Dawn's binding
// (package `webgpu`) stays outside: it is resolved from a node_modules folder
// beside or above the bundle.
import { readFile } from 'node:fs/promises';
import { fileURLToPath } from 'node:url';
import { build } from 'esbuild';

const root = fileURLToPath(new URL('../..', import.meta.url));

/** `import text from './x.wgsl?raw'`: the file's text. */
const rawText = {
  name: 'raw-text',
  setup(b) {
    b.onResolve({ filter: /\?raw$/ }, (args) => ({
      path: fileURLToPath(new URL(args.path.slice(0, -'?raw'.length), `file://${args.resolveDir}/`)),
      namespace: 'raw-text',
    }));
    b.onLoad({ filter: /.*/, namespace: 'raw-text' }, async (args) => ({ contents: await readFile(args.path, 'utf8'), loader: 'text' }));
  },
};

/** Writes the bundle to `outfile`; resolves with esbuild's warnings. */
export async function bundleBenchGpu(outfile) {
  const result = await build({
    entryPoints: [`${root}benchmarks/gpu/run.ts`],
    outfile,
    bundle: true,
    platform: 'node',
    format: 'esm',
    target: 'node20',
    external: ['webgpu'],
    plugins: [rawText],
    // CommonJS dependencies call require() for Node's modules
    banner: { js: "import { createRequire as __benchRequire } from 'node:module'; const require = __benchRequire(import.meta.url);" },
    logLevel: 'error',
    legalComments: 'none',
  });
  return result.warnings;
}
