#!/usr/bin/env node
// The GPU unit tests on a second WebGPU implementation: wgpu (with the naga
// shader compiler, as in Firefox), through Deno's navigator.gpu. Each test
// file is bundled with esbuild (WGSL `?raw` imports inlined, `vitest` and
// tests/helpers/gpu.ts replaced by tests/wgpu/*) and run in Deno on
// SwiftShader's Vulkan driver (or lavapipe, or the GPU's driver).
//
//   node scripts/test-wgpu.mjs [test files...]   (npm test runs it as the `wgpu` suite)
//
// Deno comes from the npm registry (pinned below) into .cache/deno on first use.
import { spawnSync } from 'node:child_process';
import { existsSync, mkdirSync, readdirSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { join, relative, resolve } from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';
import { SWIFTSHADER_ICD } from './setup/chromium-flags.mjs';

const root = fileURLToPath(new URL('..', import.meta.url));
const DENO_VERSION = '2.9.6';
const denoDir = join(root, '.cache', 'deno');

/** The GPU unit tests that run on wgpu too (CLI tests spawn Node and stay on Dawn). */
export const WGPU_TESTS = [
  'tests/unit/zfp/decoder.test.ts',
  'tests/unit/zfp/decode-volume.test.ts',
  'tests/unit/zfp/encoder.test.ts',
  'tests/unit/zfp/offsets.test.ts',
  'tests/unit/primitives/scan.test.ts',
  'tests/unit/primitives/compact.test.ts',
  'tests/unit/primitives/sort.test.ts',
  'tests/unit/primitives/indirect.test.ts',
  'tests/unit/gpu/grid.test.ts',
  'tests/unit/gpu/buffers.test.ts',
  'tests/unit/gpu/pipeline-cache.test.ts',
  'tests/unit/mc/case-table-wgsl.test.ts',
  'tests/unit/mc/naive-gpu.test.ts',
  'tests/unit/isosurface/block-mc.test.ts',
  'tests/unit/isosurface/vertex-format.test.ts',
  'tests/unit/isosurface/slot-ranges.test.ts',
  'tests/unit/isosurface/snapshot.test.ts',
  'tests/unit/isosurface/lru-cache.test.ts',
  'tests/unit/isosurface/no-readback.test.ts',
  'tests/unit/isosurface/behaviour.test.ts',
  'tests/unit/isosurface/pipeline.test.ts',
  'tests/unit/isosurface/normals.test.ts',
  'tests/unit/isosurface/binding-limit.test.ts',
  'tests/unit/isosurface/pipeline-cache.test.ts',
  'tests/unit/isosurface/vtk.test.ts',
  'tests/unit/isosurface/vtk-bonsai.test.ts',
  'tests/unit/store/chunked-volume.test.ts',
  'tests/unit/volume/open-volume.test.ts',
  'tests/unit/volume/tiff-isosurface.test.ts',
  'tests/unit/app/surface-layer.test.ts',
  'tests/unit/render/pipelines.test.ts',
  'tests/unit/raycast/cell-root.test.ts',
];

function findDeno() {
  const base = join(denoDir, 'node_modules', '@deno');
  if (!existsSync(base)) return undefined;
  for (const d of readdirSync(base)) {
    const exe = join(base, d, process.platform === 'win32' ? 'deno.exe' : 'deno');
    if (existsSync(exe)) return exe;
  }
  return undefined;
}

export function ensureDeno() {
  let exe = findDeno();
  if (exe && spawnSync(exe, ['--version'], { encoding: 'utf8' }).stdout?.includes(`deno ${DENO_VERSION}`)) return exe;
  console.error(`[setup] installing Deno ${DENO_VERSION} (npm package "deno") into .cache/deno for the wgpu tests...`);
  mkdirSync(denoDir, { recursive: true });
  writeFileSync(join(denoDir, 'package.json'), JSON.stringify({ private: true, description: 'Deno for scripts/test-wgpu.mjs' }) + '\n');
  const r = spawnSync('npm', ['install', '--no-audit', '--no-fund', '--no-save', '--prefix', denoDir, `deno@${DENO_VERSION}`], {
    stdio: 'inherit',
  });
  exe = findDeno();
  if (r.status !== 0 || !exe)
    throw new Error(
      `could not install Deno ${DENO_VERSION} from npm (npm install deno@${DENO_VERSION} into ${denoDir} exited with ${r.status})`,
    );
  return exe;
}

/** Vulkan driver for wgpu: ZFPISO_WGPU_ICD, else SwiftShader (Chromium's), else lavapipe, else the system's. */
function vulkanEnv() {
  if (process.env.ZFPISO_WGPU_ICD) return { VK_ICD_FILENAMES: process.env.ZFPISO_WGPU_ICD };
  const lavapipe = ['/usr/share/vulkan/icd.d/lvp_icd.x86_64.json', '/usr/share/vulkan/icd.d/lvp_icd.json'].find(existsSync);
  const icd = existsSync(SWIFTSHADER_ICD) ? SWIFTSHADER_ICD : lavapipe;
  return icd ? { VK_ICD_FILENAMES: icd, VK_LOADER_LAYERS_DISABLE: '~implicit~' } : {};
}

/** esbuild plugin: `?raw` as text, vitest and the Dawn fixture swapped, import.meta.url kept per file. */
function testPlugin() {
  const wgpuDir = join(root, 'tests', 'wgpu');
  return {
    name: 'zfpiso-wgpu',
    setup(build) {
      build.onResolve({ filter: /\?raw$/ }, (a) => ({ path: resolve(a.resolveDir, a.path.slice(0, -4)), namespace: 'raw' }));
      build.onLoad({ filter: /.*/, namespace: 'raw' }, (a) => ({ contents: readFileSync(a.path, 'utf8'), loader: 'text' }));
      build.onResolve({ filter: /^vitest$/ }, () => ({ path: join(wgpuDir, 'vitest-shim.ts') }));
      build.onResolve({ filter: /helpers\/gpu\.ts$/ }, (a) => {
        const p = resolve(a.resolveDir, a.path);
        return p === join(root, 'tests', 'helpers', 'gpu.ts') ? { path: join(wgpuDir, 'gpu.ts') } : undefined;
      });
      // Bundling moves code into one file: each module's import.meta.url
      // becomes its own source file's URL, so relative paths still work.
      build.onLoad({ filter: /\.ts$/ }, (a) => ({
        contents: readFileSync(a.path, 'utf8').replaceAll('import.meta.url', JSON.stringify(pathToFileURL(a.path).href)),
        loader: 'ts',
      }));
    },
  };
}

async function bundle(files, outDir) {
  const esbuild = await import('esbuild');
  const out = [];
  for (const file of files) {
    const entry = join(outDir, `${relative(root, file).replaceAll('/', '__')}.entry.ts`);
    writeFileSync(
      entry,
      `import { runRegistered } from ${JSON.stringify(join(root, 'tests', 'wgpu', 'harness.ts'))};\n` +
        `import ${JSON.stringify(resolve(root, file))};\n` +
        `await runRegistered(${JSON.stringify(relative(root, file))});\n`,
    );
    const outfile = entry.replace(/\.entry\.ts$/, '.mjs');
    await esbuild.build({
      entryPoints: [entry],
      outfile,
      bundle: true,
      format: 'esm',
      platform: 'node',
      target: 'es2022',
      logLevel: 'warning',
      plugins: [testPlugin()],
      external: ['webgpu'],
    });
    out.push({ file: relative(root, file), bundle: outfile });
  }
  return out;
}

export async function runWgpuTests(files = WGPU_TESTS) {
  const deno = ensureDeno();
  const outDir = join(root, 'test-results', 'wgpu');
  rmSync(outDir, { recursive: true, force: true });
  mkdirSync(outDir, { recursive: true });
  const bundles = await bundle(files, outDir);
  const env = { ...process.env, ...vulkanEnv(), DENO_NO_UPDATE_CHECK: '1', DENO_DIR: join(denoDir, 'dir'), NO_COLOR: '1' };
  console.log(
    `wgpu: ${spawnSync(deno, ['--version'], { encoding: 'utf8' }).stdout.split('\n')[0]}, VK_ICD_FILENAMES=${env.VK_ICD_FILENAMES ?? '(system drivers)'}`,
  );
  let passed = 0;
  let failed = 0;
  const times = [];
  for (const { file, bundle: b } of bundles) {
    const started = Date.now();
    const r = spawnSync(deno, ['run', '--allow-all', '--no-config', '--unstable-webgpu', b], {
      cwd: root,
      env,
      encoding: 'utf8',
      maxBuffer: 1 << 28,
      timeout: 1_200_000,
    });
    times.push({ file: relative(root, file), seconds: (Date.now() - started) / 1000 });
    const output = `${r.stdout ?? ''}${r.stderr ?? ''}`;
    const m = /WGPU-RESULT (\{.*\})/.exec(r.stdout ?? '');
    process.stdout.write((r.stdout ?? '').replace(/WGPU-RESULT .*\n?/, ''));
    if (!m) {
      failed++;
      console.log(`  ✗ ${file}: Deno exited with ${r.status ?? r.signal} before the end\n${output.split('\n').slice(-30).join('\n')}`);
      continue;
    }
    if (r.stderr?.trim())
      process.stdout.write(
        r.stderr
          .split('\n')
          .slice(-20)
          .map((l) => `      ${l}`)
          .join('\n') + '\n',
      );
    const counts = JSON.parse(m[1]);
    passed += counts.passed;
    failed += counts.failed;
  }
  return { passed, failed, files: times };
}

if (import.meta.url === pathToFileURL(process.argv[1] ?? '').href) {
  const args = process.argv.slice(2);
  const { passed, failed } = await runWgpuTests(args.length ? args.map((a) => resolve(a)) : WGPU_TESTS.map((f) => join(root, f)));
  console.log(`\n${passed} passed, ${failed} failed`);
  process.exit(failed > 0 ? 1 : 0);
}
