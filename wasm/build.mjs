#!/usr/bin/env node
// `npm run build:wasm`: fetches the library sources from the package
// registries (libtiff, zlib and libjpeg-turbo as Debian source packages,
// LASzip from the PyPI sdist of `laszip`, zfp 1.0.1 from the one vendored by
// the PyPI sdist of `hdf5plugin`),
// builds them with Debian's Emscripten, links our thin C APIs (wasm/las,
// wasm/tiff, wasm/zfp) and writes ES-module `.js` + `.wasm` pairs to
// wasm/dist/, which are committed.
//
//   node wasm/build.mjs            build and write wasm/dist/
//   node wasm/build.mjs --check    rebuild into wasm/.build/check/ and compare
//                                  byte for byte with wasm/dist/ (exit 1 if not
//                                  identical; exit 3 when emcc is absent)
//   node wasm/build.mjs --native   also build the same C APIs natively (gcc)
//                                  for the loader benchmark's native baseline
//   node wasm/build.mjs --native-only   only the native baseline (no emcc needed)
//
// Everything third-party lives in wasm/.build/ (git-ignored). The build is
// deterministic: pinned sources (wasm/sources.json, sha256-checked), fixed
// flags, no debug info, build paths mapped away with -ffile-prefix-map.
import { spawn, spawnSync } from 'node:child_process';
import { createHash } from 'node:crypto';
import { copyFileSync, existsSync, mkdirSync, readdirSync, readFileSync, rmSync, statSync, writeFileSync } from 'node:fs';
import { dirname, join, relative } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const work = join(here, '.build');
const downloads = join(work, 'downloads');
const srcRoot = join(work, 'src');
const dist = join(here, 'dist');
const sources = JSON.parse(readFileSync(join(here, 'sources.json'), 'utf8'));

const args = new Set(process.argv.slice(2));
const CHECK = args.has('--check');
const NATIVE = args.has('--native') || args.has('--native-only');
const NATIVE_ONLY = args.has('--native-only');
const JOBS = String(Math.max(1, Number(process.env.WASM_BUILD_JOBS ?? 2)));
export const EXIT_NO_EMCC = 3;

// ---------------------------------------------------------------- helpers

function log(msg) {
  console.error(`[build:wasm] ${msg}`);
}

class BuildError extends Error {}

function run(cmd, argv, { cwd = work, env = process.env, quiet = true } = {}) {
  const r = spawnSync(cmd, argv, { cwd, env, encoding: 'utf8', maxBuffer: 1 << 28, stdio: quiet ? 'pipe' : 'inherit' });
  if (r.error) throw new BuildError(`${cmd}: ${r.error.message}`);
  if (r.status !== 0) {
    const out = `${r.stdout ?? ''}${r.stderr ?? ''}`.trim().split('\n').slice(-40).join('\n');
    throw new BuildError(`command failed (exit ${r.status}): ${cmd} ${argv.join(' ')}\n${out}`);
  }
  return r.stdout ?? '';
}

function which(name) {
  const r = spawnSync('sh', ['-c', `command -v ${name}`], { encoding: 'utf8' });
  return r.status === 0 ? r.stdout.trim() : undefined;
}

const isRoot = typeof process.getuid === 'function' && process.getuid() === 0;

function sha256File(path) {
  return createHash('sha256').update(readFileSync(path)).digest('hex');
}

/** Installs Debian packages when we may (root), under the shared apt lock. */
function aptInstall(packages) {
  if (!isRoot || !which('apt-get')) {
    throw new BuildError(`missing tools; install them with: sudo apt-get install -y ${packages.join(' ')}`);
  }
  log(`installing ${packages.join(' ')} (apt-get)...`);
  const install = ['install', '-y', '-qq', '--no-install-recommends', ...packages];
  try {
    apt(install);
  } catch {
    // A fresh machine may have no package lists yet.
    apt(['update', '-qq']);
    apt(install);
  }
}

/**
 * apt-get under the shared lock (flock, from util-linux, when the machine has
 * it). Runs in / since the work folder may not exist yet (spawnSync reports a
 * missing cwd as ENOENT of the command).
 */
function apt(argv) {
  const env = { ...process.env, DEBIAN_FRONTEND: 'noninteractive' };
  if (which('flock')) run('flock', ['/tmp/apt.lock', 'apt-get', ...argv], { env, cwd: '/' });
  else run('apt-get', argv, { env, cwd: '/' });
}

// ---------------------------------------------------------------- toolchain

function emEnv() {
  // Debian's emcc needs Debian's node-acorn (TOOLCHAIN.md).
  const nodePath = ['/usr/share/nodejs', process.env.NODE_PATH].filter(Boolean).join(':');
  return { ...process.env, NODE_PATH: nodePath, EMCC_SKIP_SANITY_CHECK: '1', SOURCE_DATE_EPOCH: '0', LC_ALL: 'C' };
}

function emccVersion() {
  const out = run('emcc', ['--version'], { env: emEnv() });
  return out.split('\n')[0].trim();
}

function ensureToolchain({ install }) {
  const missing = [];
  if (!which('emcc')) missing.push('emscripten');
  if (!which('cmake')) missing.push('cmake');
  if (!which('make')) missing.push('make');
  if (!which('dpkg-source')) missing.push('dpkg-dev');
  if (missing.length === 0) return;
  if (!install) {
    if (missing.includes('emscripten')) {
      log('emcc not found: install Debian\'s Emscripten ("apt-get install emscripten") to rebuild the Wasm modules.');
      process.exit(EXIT_NO_EMCC);
    }
    throw new BuildError(`missing build tools: ${missing.join(' ')} (apt-get install ${missing.join(' ')})`);
  }
  aptInstall(missing);
}

// ---------------------------------------------------------------- sources

function hasDebSrc() {
  const r = spawnSync('apt-cache', ['showsrc', 'zlib'], { encoding: 'utf8' });
  return r.status === 0 && /^Package:/m.test(r.stdout);
}

function ensureDebSrc() {
  if (hasDebSrc()) return;
  if (!isRoot) {
    throw new BuildError(
      'apt has no deb-src entries, so "apt-get source" cannot fetch libtiff/zlib/libjpeg-turbo. ' +
        'Add "Types: deb-src" stanzas for bookworm and bookworm-security to /etc/apt/sources.list.d/ and run apt-get update.',
    );
  }
  log('adding deb-src entries for bookworm (apt)...');
  const stanza = (uri, suites) =>
    `Types: deb-src\nURIs: ${uri}\nSuites: ${suites}\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n`;
  writeFileSync(
    '/etc/apt/sources.list.d/debian-src.sources',
    `${stanza('http://deb.debian.org/debian', 'bookworm bookworm-updates')}\n${stanza('http://deb.debian.org/debian-security', 'bookworm-security')}`,
  );
  apt(['update', '-qq']);
}

function verified(files) {
  return Object.entries(files).every(([name, sum]) => existsSync(join(downloads, name)) && sha256File(join(downloads, name)) === sum);
}

function checkHashes(files) {
  for (const [name, sum] of Object.entries(files)) {
    const got = sha256File(join(downloads, name));
    if (got !== sum) throw new BuildError(`${name}: sha256 ${got} does not match the pinned ${sum} (wasm/sources.json)`);
  }
}

function fetchSources() {
  mkdirSync(downloads, { recursive: true });
  mkdirSync(srcRoot, { recursive: true });
  for (const pkg of sources.debian) {
    if (!verified(pkg.files)) {
      ensureDebSrc();
      log(`fetching Debian source ${pkg.package} ${pkg.version} (apt-get source)...`);
      try {
        run('apt-get', ['source', '--download-only', '-qq', `${pkg.package}=${pkg.version}`], { cwd: downloads });
      } catch (e) {
        throw new BuildError(
          `${e.message}\nDebian may have replaced ${pkg.package} ${pkg.version}; see "apt-cache showsrc ${pkg.package}" and update wasm/sources.json.`,
        );
      }
      checkHashes(pkg.files);
    }
    const dir = join(srcRoot, pkg.dir);
    if (!existsSync(join(dir, '.extracted'))) {
      rmSync(dir, { recursive: true, force: true });
      const dsc = Object.keys(pkg.files).find((f) => f.endsWith('.dsc'));
      // Hashes were checked above; dpkg-source applies Debian's patches (security fixes).
      run('dpkg-source', ['--no-check', '-x', join(downloads, dsc), dir], { cwd: srcRoot });
      writeFileSync(join(dir, '.extracted'), '');
    }
  }
  for (const pkg of sources.pypi) {
    const file = join(downloads, pkg.file);
    if (!existsSync(file) || sha256File(file) !== pkg.sha256) {
      log(`fetching PyPI sdist ${pkg.package}==${pkg.version} (pip download)...`);
      const req = join(downloads, `${pkg.package}-requirements.txt`);
      writeFileSync(req, `${pkg.package}==${pkg.version} --hash=sha256:${pkg.sha256}\n`);
      const python = which('python3') ?? which('python');
      if (!python) throw new BuildError('python3 with pip is needed to fetch the LASzip sdist from PyPI');
      // pipNoBinary: build an sdist's metadata with its build dependencies as wheels (--no-binary :all: would build them from source).
      run(python, [
        '-m',
        'pip',
        'download',
        '-q',
        '--disable-pip-version-check',
        '--no-deps',
        '--no-binary',
        pkg.pipNoBinary ?? ':all:',
        '--require-hashes',
        '-r',
        req,
        '-d',
        downloads,
      ]);
      checkHashes({ [pkg.file]: pkg.sha256 });
    }
    const dir = join(srcRoot, `${pkg.package}-${pkg.version}`);
    if (!existsSync(join(dir, '.extracted'))) {
      rmSync(dir, { recursive: true, force: true });
      // `extract`: only these members of a large archive (hdf5plugin: zfp's tree).
      run('tar', ['-xzf', file, '-C', srcRoot, ...(pkg.extract ?? [])]);
      writeFileSync(join(dir, '.extracted'), '');
    }
  }
}

function pypiSource(name) {
  const pkg = sources.pypi.find((p) => p.package === name);
  if (!pkg) throw new BuildError(`wasm/sources.json has no PyPI entry for ${name}`);
  return pkg;
}

function laszipDir() {
  const vendor = join(srcRoot, `laszip-${pypiSource('laszip').version}`, 'src', 'vendor');
  const name = readdirSync(vendor).find((n) => n.startsWith('LASzip'));
  if (!name) throw new BuildError(`no LASzip source under ${vendor}`);
  return join(vendor, name);
}

// ---------------------------------------------------------------- libraries

// One set of flags for everything; build paths are mapped to /build so no
// absolute path of this checkout ends up in the output.
const OPT = ['-O3', '-DNDEBUG'];
const prefixMap = () => [`-ffile-prefix-map=${work}=/build`, `-ffile-prefix-map=${here}=/wasm`];

const LASZIP_SOURCES = [
  'mydefs.cpp',
  'lasmessage.cpp',
  'arithmeticdecoder.cpp',
  'arithmeticencoder.cpp',
  'arithmeticmodel.cpp',
  'integercompressor.cpp',
  'lasindex.cpp',
  'lasinterval.cpp',
  'lasquadtree.cpp',
  'lasreaditemcompressed_v1.cpp',
  'lasreaditemcompressed_v2.cpp',
  'lasreaditemcompressed_v3.cpp',
  'lasreaditemcompressed_v4.cpp',
  'lasreadpoint.cpp',
  'laswriteitemcompressed_v1.cpp',
  'laswriteitemcompressed_v2.cpp',
  'laswriteitemcompressed_v3.cpp',
  'laswriteitemcompressed_v4.cpp',
  'laswritepoint.cpp',
  'laszip.cpp',
  'laszip_dll.cpp',
];
// zfp 1.0.1's library (src/CMakeLists.txt of zfp: every codec, bitstream, zfp.c).
const ZFP_SOURCES = [
  'bitstream.c',
  'zfp.c',
  ...['1', '2', '3', '4'].flatMap((d) => ['f', 'd', 'i', 'l'].flatMap((t) => [`decode${d}${t}.c`, `encode${d}${t}.c`])),
];
// The zfp 1.0.1 release as hdf5plugin's sdist vendors it (zfpy's sdist lacks include/zfp/bitstream.inl).
const zfpDir = () => join(srcRoot, `hdf5plugin-${pypiSource('hdf5plugin').version}`, 'lib', 'zfp');
const ZLIB_SOURCES = [
  'adler32.c',
  'compress.c',
  'crc32.c',
  'deflate.c',
  'infback.c',
  'inffast.c',
  'inflate.c',
  'inftrees.c',
  'trees.c',
  'uncompr.c',
  'zutil.c',
];

// CMake's check_type_size misreads sizes under Debian's Emscripten toolchain
// file (it reported sizeof(size_t) = 9): give wasm32's sizes outright.
const WASM32_TYPE_SIZES = [
  ['SIZE_T', 4],
  ['UNSIGNED_LONG', 4],
  ['LONG', 4],
  ['UNSIGNED_LONG_LONG', 8],
  ['LONG_LONG', 8],
  ['UNSIGNED_INT', 4],
  ['INT', 4],
  ['SIGNED_LONG', 4],
  ['SIGNED_LONG_LONG', 8],
  ['UNSIGNED_CHAR_P', 4],
  ['SIGNED_INT', 4],
  ['SIGNED_SHORT', 2],
  ['UNSIGNED_SHORT', 2],
  ['UNSIGNED_CHAR', 1],
  ['SIGNED_CHAR', 1],
  ['SHORT', 2],
  ['VOID_P', 4],
  ['PTRDIFF_T', 4],
].flatMap(([t, n]) => [`-DSIZEOF_${t}=${n}`, `-DHAVE_SIZEOF_${t}=TRUE`]);
// libjpeg-turbo names its check_type_size results without the SIZEOF_ prefix.
const WASM32_JPEG_TYPE_SIZES = ['-DSIZE_T=4', '-DHAVE_SIZE_T=TRUE', '-DUNSIGNED_LONG=4', '-DHAVE_UNSIGNED_LONG=TRUE'];

/** A toolchain: Emscripten for the modules, or the host compiler for the native baseline. */
function toolchain(kind) {
  if (kind === 'wasm') {
    return {
      kind,
      cc: 'emcc',
      cxx: 'em++',
      ar: 'emar',
      env: emEnv(),
      cmake: (argv) => ['emcmake', ['cmake', ...argv]],
      cflags: [...OPT, ...prefixMap()],
      // LASzip reports truncated data by throwing; Debian's prebuilt
      // libraries support Emscripten's JS-based exception catching.
      cxxflags: [...OPT, ...prefixMap(), '-fexceptions'],
      prefix: join(work, 'prefix-wasm'),
    };
  }
  return {
    kind,
    cc: 'gcc',
    cxx: 'g++',
    ar: 'ar',
    env: { ...process.env, LC_ALL: 'C' },
    cmake: (argv) => ['cmake', argv],
    cflags: [...OPT, '-fPIC', ...prefixMap()],
    cxxflags: [...OPT, '-fPIC', ...prefixMap()],
    prefix: join(work, 'prefix-native'),
  };
}

async function compileArchive(tc, name, dir, files, flags, isCxx) {
  const objDir = join(tc.prefix, 'obj', name);
  rmSync(objDir, { recursive: true, force: true });
  mkdirSync(objDir, { recursive: true });
  const objects = files.map((f) => join(objDir, f.replace(/[/.]/g, '_') + '.o'));
  const compileOne = (i) =>
    new Promise((resolveP, reject) => {
      const child = spawn(isCxx ? tc.cxx : tc.cc, [...flags, '-c', join(dir, files[i]), '-o', objects[i]], { cwd: dir, env: tc.env });
      let err = '';
      child.stderr.on('data', (d) => (err += d));
      child.on('error', (e) => reject(new BuildError(`${tc.cc}: ${e.message}`)));
      child.on('close', (code) => (code === 0 ? resolveP() : reject(new BuildError(`compiling ${files[i]} failed:\n${err}`))));
    });
  let next = 0;
  const worker = async () => {
    while (next < files.length) await compileOne(next++);
  };
  await Promise.all(Array.from({ length: Number(JOBS) }, worker));
  const lib = join(tc.prefix, 'lib', `lib${name}.a`);
  mkdirSync(dirname(lib), { recursive: true });
  rmSync(lib, { force: true });
  // Deterministic archive (no timestamps/uids), members in a fixed order.
  run(tc.ar, ['rcsD', lib, ...objects], { env: tc.env });
  return lib;
}

async function buildZlib(tc) {
  const dir = join(srcRoot, sources.debian.find((p) => p.package === 'zlib').dir);
  await compileArchive(tc, 'z', dir, ZLIB_SOURCES, [...tc.cflags, '-DHAVE_UNISTD_H', '-DHAVE_STDARG_H'], false);
  mkdirSync(join(tc.prefix, 'include'), { recursive: true });
  for (const h of ['zlib.h', 'zconf.h']) copyFileSync(join(dir, h), join(tc.prefix, 'include', h));
}

function cmakeBuild(tc, name, srcDir, cmakeArgs, target) {
  const buildDir = join(work, `build-${tc.kind}-${name}`);
  rmSync(buildDir, { recursive: true, force: true });
  mkdirSync(buildDir, { recursive: true });
  const [cmd, argv] = tc.cmake([
    srcDir,
    '-G',
    'Unix Makefiles',
    '-DCMAKE_BUILD_TYPE=Release',
    `-DCMAKE_C_FLAGS=${tc.cflags.join(' ')}`,
    `-DCMAKE_C_FLAGS_RELEASE=`,
    `-DCMAKE_INSTALL_PREFIX=${tc.prefix}`,
    '-DBUILD_SHARED_LIBS=OFF',
    ...(tc.kind === 'native' ? [`-DCMAKE_C_COMPILER=${tc.cc}`] : []),
    ...cmakeArgs,
  ]);
  run(cmd, argv, { cwd: buildDir, env: tc.env });
  run('make', [`-j${JOBS}`, target], { cwd: buildDir, env: tc.env });
  return buildDir;
}

function buildJpeg(tc) {
  const dir = join(srcRoot, sources.debian.find((p) => p.package === 'libjpeg-turbo').dir);
  const b = cmakeBuild(
    tc,
    'jpeg',
    dir,
    [
      '-DENABLE_SHARED=OFF',
      '-DENABLE_STATIC=ON',
      '-DWITH_SIMD=OFF',
      '-DWITH_TURBOJPEG=OFF',
      '-DWITH_JAVA=OFF',
      '-DWITH_12BIT=OFF',
      ...(tc.kind === 'wasm' ? WASM32_JPEG_TYPE_SIZES : []),
    ],
    'jpeg-static',
  );
  mkdirSync(join(tc.prefix, 'lib'), { recursive: true });
  copyFileSync(join(b, 'libjpeg.a'), join(tc.prefix, 'lib', 'libjpeg.a'));
  for (const h of ['jpeglib.h', 'jmorecfg.h', 'jerror.h']) copyFileSync(join(dir, h), join(tc.prefix, 'include', h));
  copyFileSync(join(b, 'jconfig.h'), join(tc.prefix, 'include', 'jconfig.h'));
}

function buildTiff(tc) {
  const dir = join(srcRoot, sources.debian.find((p) => p.package === 'tiff').dir);
  const inc = join(tc.prefix, 'include');
  const lib = join(tc.prefix, 'lib');
  const b = cmakeBuild(
    tc,
    'tiff',
    dir,
    [
      '-Dtiff-tools=OFF',
      '-Dtiff-tests=OFF',
      '-Dtiff-contrib=OFF',
      '-Dtiff-docs=OFF',
      '-Dtiff-deprecated=OFF',
      '-Dtiff-install=OFF',
      '-Dcxx=OFF',
      '-Dld-version-script=OFF',
      '-Dtiff-opengl=OFF',
      ...(tc.kind === 'wasm' ? WASM32_TYPE_SIZES : []),
      '-Dzlib=ON',
      `-DZLIB_INCLUDE_DIR=${inc}`,
      `-DZLIB_LIBRARY=${join(lib, 'libz.a')}`,
      '-Djpeg=ON',
      '-Dold-jpeg=ON',
      '-Djpeg12=OFF',
      `-DJPEG_INCLUDE_DIR=${inc}`,
      `-DJPEG_LIBRARY=${join(lib, 'libjpeg.a')}`,
      '-Dpixarlog=ON',
      '-Dlzma=OFF',
      '-Dzstd=OFF',
      '-Dwebp=OFF',
      '-Djbig=OFF',
      '-Dlerc=OFF',
      '-Dlibdeflate=OFF',
    ],
    'tiff',
  );
  copyFileSync(join(b, 'libtiff', 'libtiff.a'), join(lib, 'libtiff.a'));
  for (const h of ['tiffio.h', 'tiff.h', 'tiffvers.h']) copyFileSync(join(dir, 'libtiff', h), join(inc, h));
  for (const h of ['tiffconf.h']) copyFileSync(join(b, 'libtiff', h), join(inc, h));
}

async function buildLaszip(tc) {
  const dir = laszipDir();
  await compileArchive(
    tc,
    'laszip',
    join(dir, 'src'),
    LASZIP_SOURCES,
    [
      ...tc.cxxflags,
      '-std=c++17',
      '-DLASZIPDLL_EXPORTS',
      '-DUNORDERED',
      '-DHAVE_UNORDERED_MAP=1',
      '-Wno-format-security',
      `-I${join(dir, 'include', 'laszip')}`,
      `-I${join(dir, 'include')}`,
      `-I${join(dir, 'src')}`,
    ],
    true,
  );
}

async function buildZfp(tc) {
  const dir = zfpDir();
  await compileArchive(tc, 'zfp', join(dir, 'src'), ZFP_SOURCES, [...tc.cflags, '-std=c11', `-I${join(dir, 'include')}`], false);
}

function libraryStamp(tc) {
  const h = createHash('sha256');
  h.update(
    JSON.stringify({
      sources,
      tc: { ...tc, env: undefined, cmake: undefined },
      LASZIP_SOURCES,
      ZLIB_SOURCES,
      ZFP_SOURCES,
      WASM32_TYPE_SIZES,
      WASM32_JPEG_TYPE_SIZES,
    }),
  );
  // The library recipes themselves (editing the rest of this script keeps the cache).
  for (const fn of [compileArchive, cmakeBuild, buildZlib, buildJpeg, buildTiff, buildLaszip, buildZfp]) h.update(fn.toString());
  if (tc.kind === 'wasm') h.update(emccVersion());
  return h.digest('hex');
}

async function buildLibraries(tc) {
  const stampFile = join(tc.prefix, '.stamp');
  const stamp = libraryStamp(tc);
  if (existsSync(stampFile) && readFileSync(stampFile, 'utf8') === stamp) {
    log(`libraries (${tc.kind}) are up to date`);
    return;
  }
  rmSync(tc.prefix, { recursive: true, force: true });
  mkdirSync(join(tc.prefix, 'include'), { recursive: true });
  for (const [name, fn] of [
    ['zlib', buildZlib],
    ['libjpeg-turbo', buildJpeg],
    ['libtiff', buildTiff],
    ['LASzip', buildLaszip],
    ['zfp', buildZfp],
  ]) {
    log(`building ${name} (${tc.kind})...`);
    await fn(tc);
  }
  writeFileSync(stampFile, stamp);
}

// ---------------------------------------------------------------- modules

const LAS_EXPORTS = [
  '_malloc',
  '_free',
  '_las_open',
  '_las_error',
  '_las_info',
  '_las_header_string',
  '_las_read',
  '_las_outside',
  '_las_close',
];
const ZFP_EXPORTS = ['_malloc', '_free', '_zfp_api_info', '_zfp_api_decode', '_zfp_api_decode_raw', '_zfp_api_error'];
const TIFF_EXPORTS = [
  '_malloc',
  '_free',
  '_tiff_open',
  '_tiff_error',
  '_tiff_page_count',
  '_tiff_page_info',
  '_tiff_page_description',
  '_tiff_page_bytes',
  '_tiff_read_page',
  '_tiff_close',
];

function moduleFlags(exportName, exportsList) {
  return [
    '-O3',
    '-sMODULARIZE=1',
    '-sEXPORT_ES6=1',
    `-sEXPORT_NAME=${exportName}`,
    // The loaders hand the module its .wasm bytes (Node) or URL (Vite), so
    // the glue needs no Node-specific code.
    '-sENVIRONMENT=web,worker',
    '-sFILESYSTEM=0',
    '-sALLOW_MEMORY_GROWTH=1',
    '-sINITIAL_MEMORY=16MB',
    '-sMAXIMUM_MEMORY=4GB',
    '-sDYNAMIC_EXECUTION=0',
    '-sTEXTDECODER=2',
    '-sASSERTIONS=0',
    `-sEXPORTED_FUNCTIONS=${exportsList.join(',')}`,
    '-sEXPORTED_RUNTIME_METHODS=UTF8ToString',
  ];
}

function linkModules(tc, outDir) {
  const inc = join(tc.prefix, 'include');
  const lib = join(tc.prefix, 'lib');
  const lz = laszipDir();
  mkdirSync(outDir, { recursive: true });
  log('linking las.js/las.wasm...');
  run(
    'em++',
    [
      ...tc.cxxflags,
      '-std=c++17',
      `-I${join(lz, 'dll')}`,
      `-I${join(lz, 'include')}`,
      `-I${join(lz, 'include', 'laszip')}`,
      join(here, 'las', 'las_api.cpp'),
      join(lib, 'liblaszip.a'),
      ...moduleFlags('createLasModule', LAS_EXPORTS),
      '-o',
      join(outDir, 'las.js'),
    ],
    { env: tc.env, cwd: here },
  );
  log('linking tiff.js/tiff.wasm...');
  run(
    'emcc',
    [
      ...tc.cflags,
      `-I${inc}`,
      join(here, 'tiff', 'tiff_api.c'),
      join(lib, 'libtiff.a'),
      join(lib, 'libjpeg.a'),
      join(lib, 'libz.a'),
      ...moduleFlags('createTiffModule', TIFF_EXPORTS),
      '-o',
      join(outDir, 'tiff.js'),
    ],
    { env: tc.env, cwd: here },
  );
  log('linking zfp.js/zfp.wasm...');
  run(
    'emcc',
    [
      ...tc.cflags,
      '-std=c11',
      `-I${join(zfpDir(), 'include')}`,
      join(here, 'zfp', 'zfp_api.c'),
      join(lib, 'libzfp.a'),
      ...moduleFlags('createZfpModule', ZFP_EXPORTS),
      '-o',
      join(outDir, 'zfp.js'),
    ],
    { env: tc.env, cwd: here },
  );
  const outputs = ['las.js', 'las.wasm', 'tiff.js', 'tiff.wasm', 'zfp.js', 'zfp.wasm'];
  const info = {
    comment: 'Written by wasm/build.mjs; `npm run build:wasm -- --check` rebuilds and compares these files byte for byte.',
    emcc: emccVersion(),
    libraries: {
      LASzip: `${laszipVersion()} (PyPI laszip==${pypiSource('laszip').version} sdist)`,
      libtiff: `Debian tiff ${sources.debian.find((p) => p.package === 'tiff').version}`,
      zlib: `Debian zlib ${sources.debian.find((p) => p.package === 'zlib').version}`,
      libjpeg: `Debian libjpeg-turbo ${sources.debian.find((p) => p.package === 'libjpeg-turbo').version}`,
      zfp: `zfp ${zfpVersion()} (lib/zfp of the PyPI hdf5plugin==${pypiSource('hdf5plugin').version} sdist)`,
    },
    flags: {
      c: tc.cflags.filter((f) => !f.startsWith('-ffile-prefix-map')),
      cxx: tc.cxxflags.filter((f) => !f.startsWith('-ffile-prefix-map')),
      las: moduleFlags('createLasModule', LAS_EXPORTS),
      tiff: moduleFlags('createTiffModule', TIFF_EXPORTS),
      zfp: moduleFlags('createZfpModule', ZFP_EXPORTS),
    },
    files: Object.fromEntries(outputs.map((f) => [f, { bytes: statSync(join(outDir, f)).size, sha256: sha256File(join(outDir, f)) }])),
  };
  writeFileSync(join(outDir, 'build-info.json'), JSON.stringify(info, null, 2) + '\n');
  return [...outputs, 'build-info.json'];
}

function zfpVersion() {
  const h = readFileSync(join(zfpDir(), 'include', 'zfp', 'version.h'), 'utf8');
  const v = ['MAJOR', 'MINOR', 'PATCH'].map((k) => new RegExp(`ZFP_VERSION_${k}\\s+(\\d+)`).exec(h)?.[1] ?? '?');
  return v.join('.');
}

function laszipVersion() {
  const h = readFileSync(join(laszipDir(), 'include', 'laszip', 'laszip_api_version.h'), 'utf8');
  const v = ['MAJOR', 'MINOR', 'PATCH'].map((k) => new RegExp(`LASZIP_API_VERSION_${k}\\s+(\\d+)`).exec(h)?.[1] ?? '?');
  return `LASzip ${v.join('.')}`;
}

// ---------------------------------------------------------------- native baseline

async function buildNative() {
  if (!which('gcc') || !which('g++')) throw new BuildError('gcc/g++ are needed for the native baseline (apt-get install build-essential)');
  const tc = toolchain('native');
  await buildLibraries(tc);
  const lz = laszipDir();
  const out = join(work, 'native');
  mkdirSync(out, { recursive: true });
  log('linking native las_bench and tiff_bench...');
  run(
    'g++',
    [
      ...tc.cxxflags,
      '-std=c++17',
      `-I${join(lz, 'dll')}`,
      `-I${join(lz, 'include')}`,
      `-I${join(lz, 'include', 'laszip')}`,
      `-I${join(here, 'las')}`,
      join(here, 'las', 'las_api.cpp'),
      join(here, 'native', 'las_bench.cpp'),
      join(tc.prefix, 'lib', 'liblaszip.a'),
      '-o',
      join(out, 'las_bench'),
    ],
    { env: tc.env },
  );
  const inc = join(tc.prefix, 'include');
  const lib = join(tc.prefix, 'lib');
  run(
    'gcc',
    [
      ...tc.cflags,
      `-I${inc}`,
      join(here, 'tiff', 'tiff_api.c'),
      join(here, 'native', 'tiff_bench.c'),
      join(lib, 'libtiff.a'),
      join(lib, 'libjpeg.a'),
      join(lib, 'libz.a'),
      '-lm',
      '-o',
      join(out, 'tiff_bench'),
    ],
    { env: tc.env },
  );
  log(`native baseline in ${relative(process.cwd(), out)}`);
}

// ---------------------------------------------------------------- main

async function main() {
  if (NATIVE_ONLY) {
    const missing = ['cmake', 'make', 'dpkg-source', 'gcc', 'g++'].filter((t) => !which(t));
    if (missing.length > 0)
      aptInstall(missing.map((t) => ({ 'dpkg-source': 'dpkg-dev', gcc: 'build-essential', 'g++': 'build-essential' })[t] ?? t));
    mkdirSync(work, { recursive: true });
    fetchSources();
    await buildNative();
    return;
  }
  ensureToolchain({ install: !CHECK });
  mkdirSync(work, { recursive: true });
  fetchSources();
  const tc = toolchain('wasm');
  await buildLibraries(tc);
  if (CHECK) {
    const outDir = join(work, 'check');
    rmSync(outDir, { recursive: true, force: true });
    const files = linkModules(tc, outDir);
    const differ = files.filter((f) => !existsSync(join(dist, f)) || !readFileSync(join(dist, f)).equals(readFileSync(join(outDir, f))));
    if (differ.length > 0) {
      log(`NOT reproducible: ${differ.join(', ')} differ from wasm/dist/ (rebuilt copies in ${relative(process.cwd(), outDir)})`);
      process.exit(1);
    }
    log(`reproducible: ${files.join(', ')} are identical to wasm/dist/`);
  } else {
    const files = linkModules(tc, dist);
    for (const f of files) log(`wrote wasm/dist/${f} (${statSync(join(dist, f)).size} bytes)`);
  }
  if (NATIVE) await buildNative();
}

main().catch((e) => {
  if (e instanceof BuildError) {
    log(`error: ${e.message}`);
    process.exit(1);
  }
  throw e;
});
