// The dependency rule of src/ (issue 18): folders form layers, and a module
// imports only from its own folder or from lower layers, so dependencies point
// one way (pages and tools on top, the GPU kit at the bottom) and there is no
// import loop, between folders or between files. src/ never imports the
// benchmarks, the tests or the scripts; built artefacts (wasm/dist) and WGSL
// (shaders/) are leaves. A new folder must be given its layer here.
import { readdirSync, readFileSync, statSync } from 'node:fs';
import { dirname, join, relative, resolve } from 'node:path';
import { describe, expect, test } from 'vitest';

const root = resolve(import.meta.dirname, '../../..');
const src = join(root, 'src');

/** Higher layers may import lower ones; folders in one layer may not import each other. */
const LAYERS: Record<string, number> = {
  core: 0, // dims, the file-naming rule, data types, the default view direction
  util: 0,
  gpu: 1,
  primitives: 2,
  zfp: 3,
  mc: 3,
  raycast: 3, // the exact ray-cell crossing (issue 46), a per-cell algorithm as marching cubes' tables; the layer that draws with it is render's
  loaders: 3,
  formats: 4,
  volume: 5,
  isosurface: 6,
  render: 7,
  store: 7, // streaming Zarr stores: above the pipeline it feeds, beside the renderer
  bench: 8,
  app: 9,
  examples: 10,
  cli: 10,
};

/** Where a src module may reach outside src/ (leaves that import nothing of ours). */
const OUTSIDE_ALLOWED = ['shaders/', 'wasm/dist/'];

function sources(dir: string): string[] {
  const out: string[] = [];
  for (const name of readdirSync(dir)) {
    const path = join(dir, name);
    if (statSync(path).isDirectory()) out.push(...sources(path));
    else if (/\.ts$/.test(name) && !name.endsWith('.d.ts')) out.push(path);
  }
  return out;
}

/** Relative specifiers of static imports, re-exports and dynamic imports with a literal. */
function importsOf(text: string): string[] {
  const code = text.replace(/\/\*[\s\S]*?\*\//g, '').replace(/^\s*\/\/.*$/gm, '');
  const specs = new Set<string>();
  for (const m of code.matchAll(/(?:\bfrom\s*|\bimport\s*\(\s*|^\s*import\s+)['"]([^'"]+)['"]/gm)) specs.add(m[1]);
  return [...specs].filter((s) => s.startsWith('.'));
}

const folderOf = (file: string) => relative(src, file).split('/')[0];

const files = sources(src);
const edges = new Map<string, string[]>();
for (const file of files) {
  edges.set(
    file,
    importsOf(readFileSync(file, 'utf8')).map((spec) => resolve(dirname(file), spec.replace(/\?raw$/, ''))),
  );
}

describe('layers of src/', () => {
  test('every folder has a layer', () => {
    const folders = [...new Set(files.map(folderOf))].filter((f) => !f.endsWith('.ts'));
    expect(folders.filter((f) => !(f in LAYERS))).toEqual([]);
  });

  test('imports point down the layers (or stay in the folder), never into benchmarks, tests or scripts', () => {
    const wrong: string[] = [];
    for (const [file, targets] of edges) {
      const from = folderOf(file);
      for (const target of targets) {
        const rel = relative(root, target);
        const where = `${relative(root, file)} imports ${rel}`;
        if (!rel.startsWith('src/')) {
          if (!OUTSIDE_ALLOWED.some((p) => rel.startsWith(p))) wrong.push(`${where} (outside src/)`);
          continue;
        }
        const to = folderOf(target);
        if (to === from) continue;
        if (!(LAYERS[to] < LAYERS[from])) wrong.push(`${where} (${from}: layer ${LAYERS[from]}, ${to}: layer ${LAYERS[to]})`);
      }
    }
    expect(wrong).toEqual([]);
  });

  test('no import loop between files', () => {
    const state = new Map<string, 'open' | 'done'>();
    const loops: string[] = [];
    const visit = (file: string, path: string[]): void => {
      if (state.get(file) === 'done') return;
      if (state.get(file) === 'open') {
        loops.push([...path.slice(path.indexOf(file)), file].map((f) => relative(src, f)).join(' -> '));
        return;
      }
      state.set(file, 'open');
      for (const t of edges.get(file) ?? []) if (edges.has(t)) visit(t, [...path, file]);
      state.set(file, 'done');
    };
    for (const file of files) visit(file, []);
    expect(loops).toEqual([]);
  });

  test('the checker sees imports (it could fail)', () => {
    expect(
      importsOf(
        `import a from './a.ts';\nexport { b } from "../b.ts";\nconst c = await import('./c.ts');\n// import d from './d.ts';\nimport 'x';\nimport wgsl from '../../shaders/e.wgsl?raw';`,
      ),
    ).toEqual(['./a.ts', '../b.ts', './c.ts', '../../shaders/e.wgsl?raw']);
    expect(edges.size).toBeGreaterThan(100);
  });
});
