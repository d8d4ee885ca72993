// `npm run bench:gpu -- --pack`: everything bench:gpu needs on a bare machine
// with a GPU that reaches no registry, in .gpu-bundle/ (ignored by git, named
// in the device call's `carry`), under the 64 MiB a device call may carry with
// the working tree:
//   bench-gpu.mjs            the benchmark and the product code, one file (bundle.mjs)
//   node.xz                  this machine's Node binary, xz-compressed
//   node_modules/webgpu/     Dawn's binding for linux-x64 (dawn.node.xz) and its loader
//   gl/*.deb                 the Vulkan loader and GL dispatch libraries (Debian, amd64)
//   wheels/*.whl             the converter's Python packages the device image lacks (CPython 3.12)
//   data/                    the reference volume and shared/data/reference/mc.json
// benchmarks/gpu/device.sh unpacks and runs it there.
import { execFileSync, execSync } from 'node:child_process';
import { copyFileSync, existsSync, mkdirSync, readdirSync, readFileSync, rmSync, statSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { bundleBenchGpu } from './bundle.mjs';

const root = fileURLToPath(new URL('../..', import.meta.url));
const out = join(root, '.gpu-bundle');
const MiB = 2 ** 20;
/** What a device call carries at most, working tree included. */
const CARRY_LIMIT = 64 * MiB;

// The converter's packages missing from the device image (its numpy, dask's
// and zarr's other needs are there), at the converter's pins, for CPython 3.12.
const WHEELS = [
  'zfpy==1.0.1',
  'numcodecs==0.16.6',
  'zarr==3.1.6',
  'dask==2026.8.0',
  'crc32c==2.9.post0',
  'donfig==0.8.1.post1',
  'google-crc32c==1.9.0',
  'partd==1.4.2',
  'locket==1.0.0',
];
const DEBS = ['libvulkan1', 'libegl1', 'libglvnd0', 'libopengl0', 'libgl1', 'libglx0', 'libgles2'];
const DATA = ['volumes/bonsai_256x256x256_float32.rate4.zfp', 'reference/mc.json', 'reference/mc_spec.json'];

function sizeOf(path) {
  const s = statSync(path);
  if (!s.isDirectory()) return s.size;
  return readdirSync(path).reduce((n, e) => n + sizeOf(join(path, e)), 0);
}

function step(what, fn) {
  const t0 = performance.now();
  process.stdout.write(`[pack] ${what}... `);
  const r = fn();
  console.log(`${((performance.now() - t0) / 1000).toFixed(1)} s`);
  return r;
}

/** xz -9 of `from` into `to`, skipped when `to` was made from the same bytes (a stamp of size and mtime). */
function xz(from, to) {
  const s = statSync(from);
  const stamp = `${s.size}:${s.mtimeMs}`;
  const cache = join(root, '.cache', 'gpu-bundle', to.replaceAll('/', '_'));
  if (existsSync(cache) && existsSync(`${cache}.stamp`) && readFileSync(`${cache}.stamp`, 'utf8') === stamp) {
    copyFileSync(cache, to);
    return;
  }
  mkdirSync(join(root, '.cache', 'gpu-bundle'), { recursive: true });
  execSync(`xz -9 -T0 -c "${from}" > "${cache}"`);
  writeFileSync(`${cache}.stamp`, stamp);
  copyFileSync(cache, to);
}

export async function pack() {
  if (process.platform !== 'linux' || process.arch !== 'x64')
    throw new Error(`the bundle carries this machine's Node and Dawn for linux-x64; this is ${process.platform}-${process.arch}`);
  rmSync(out, { recursive: true, force: true });
  mkdirSync(out, { recursive: true });
  const t0 = performance.now();
  process.stdout.write('[pack] bundling the benchmark... ');
  await bundleBenchGpu(join(out, 'bench-gpu.mjs'));
  console.log(`${((performance.now() - t0) / 1000).toFixed(1)} s`);

  step(`compressing Node ${process.version}`, () => xz(process.execPath, join(out, 'node.xz')));
  const webgpuFrom = join(root, 'node_modules', 'webgpu');
  const webgpuTo = join(out, 'node_modules', 'webgpu');
  mkdirSync(join(webgpuTo, 'dist', 'linux-x64'), { recursive: true });
  for (const f of ['package.json', 'index.js', 'LICENSE.md']) copyFileSync(join(webgpuFrom, f), join(webgpuTo, f));
  step("compressing Dawn's binding (dawn.node)", () =>
    xz(join(webgpuFrom, 'dist', 'linux-x64', 'dawn.node'), join(webgpuTo, 'dist', 'linux-x64', 'dawn.node.xz')),
  );

  step('downloading the Vulkan loader packages (amd64)', () => {
    mkdirSync(join(out, 'gl'), { recursive: true });
    const lists = join(root, '.cache', 'gpu-bundle', 'apt-lists');
    mkdirSync(join(lists, 'partial'), { recursive: true });
    const o = ['-oAPT::Architecture=amd64', '-oAPT::Architectures=amd64', `-oDir::State::Lists=${lists}`];
    execFileSync('apt-get', [...o, 'update', '-qq'], { stdio: 'ignore' });
    execFileSync('apt-get', [...o, 'download', ...DEBS], { cwd: join(out, 'gl'), stdio: 'ignore' });
  });
  step('downloading the converter wheels (CPython 3.12, manylinux x86_64)', () => {
    const platforms = [
      'manylinux_2_28_x86_64',
      'manylinux_2_17_x86_64',
      'manylinux2014_x86_64',
      'manylinux_2_5_x86_64',
      'manylinux1_x86_64',
    ];
    execFileSync(
      'python3',
      [
        ...['-m', 'pip', 'download', '-q', '--no-deps', '--only-binary=:all:', '--python-version', '3.12', '--implementation', 'cp'],
        ...platforms.flatMap((p) => ['--platform', p]),
        ...['-d', join(out, 'wheels'), ...WHEELS],
      ],
      { stdio: 'inherit' },
    );
  });
  const shared = join(root, '..', 'shared', 'data');
  for (const f of DATA) {
    mkdirSync(join(out, 'data', f, '..'), { recursive: true });
    copyFileSync(join(shared, f), join(out, 'data', f));
  }

  const bundle = sizeOf(out);
  const tracked = execSync('git ls-files -z', { cwd: root, encoding: 'buffer' })
    .toString()
    .split('\0')
    .filter(Boolean)
    .reduce((n, f) => n + (existsSync(join(root, f)) ? statSync(join(root, f)).size : 0), 0);
  console.log(
    `[pack] .gpu-bundle: ${(bundle / MiB).toFixed(1)} MiB; with the tracked files (${(tracked / MiB).toFixed(1)} MiB) ${((bundle + tracked) / MiB).toFixed(1)} of the ${CARRY_LIMIT / MiB} MiB a device call carries`,
  );
  for (const e of readdirSync(out)) console.log(`  ${e}: ${(sizeOf(join(out, e)) / MiB).toFixed(1)} MiB`);
  if (bundle + tracked > CARRY_LIMIT) throw new Error('the bundle and the working tree are over what a device call carries');
  console.log("[pack] run it on a lent GPU: benchmarks/gpu/README.md (device run with carry ['.gpu-bundle'])");
}
