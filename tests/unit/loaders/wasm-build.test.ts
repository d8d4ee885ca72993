// The committed Wasm modules (wasm/dist) are what wasm/build.mjs writes, and
// the build reproduces them byte for byte. The rebuild needs Debian's emcc;
// without it that test is skipped with the reason (the loader tests still run
// on the committed modules).
import { spawnSync } from 'node:child_process';
import { createHash } from 'node:crypto';
import { readFileSync } from 'node:fs';
import { fileURLToPath } from 'node:url';
import { describe, expect, test } from 'vitest';
import { loadLasWasm } from '../../../src/loaders/las.ts';
import { loadTiffWasm } from '../../../src/loaders/tiff.ts';

const wasmDir = fileURLToPath(new URL('../../../wasm/', import.meta.url));
const info = JSON.parse(readFileSync(`${wasmDir}dist/build-info.json`, 'utf8'));
const hasEmcc = spawnSync('sh', ['-c', 'command -v emcc'], { encoding: 'utf8' }).status === 0;

describe('committed Wasm modules', () => {
  test('files match build-info.json (sizes and sha256)', () => {
    for (const name of ['las.js', 'las.wasm', 'tiff.js', 'tiff.wasm', 'zfp.js', 'zfp.wasm']) {
      const bytes = readFileSync(`${wasmDir}dist/${name}`);
      expect(bytes.length, name).toBe(info.files[name].bytes);
      expect(createHash('sha256').update(bytes).digest('hex'), name).toBe(info.files[name].sha256);
    }
    expect(info.libraries.LASzip).toMatch(/^LASzip 3\.\d+\.\d+/);
    expect(info.libraries.libtiff).toMatch(/^Debian tiff 4\./);
    expect(info.libraries.zfp).toMatch(/^zfp 1\.0\.1 /);
  });

  test('both modules start and export their C API', async () => {
    const las = await loadLasWasm();
    for (const f of ['_las_open', '_las_error', '_las_info', '_las_header_string', '_las_read', '_las_close', '_malloc', '_free']) {
      expect(typeof (las as unknown as Record<string, unknown>)[f], f).toBe('function');
    }
    const tiff = await loadTiffWasm();
    for (const f of [
      '_tiff_open',
      '_tiff_error',
      '_tiff_page_count',
      '_tiff_page_info',
      '_tiff_page_bytes',
      '_tiff_read_page',
      '_tiff_close',
    ]) {
      expect(typeof (tiff as unknown as Record<string, unknown>)[f], f).toBe('function');
    }
  });
});

describe('reproducible build', () => {
  test('npm run build:wasm -- --check rebuilds wasm/dist byte for byte', (ctx) => {
    if (!hasEmcc) {
      ctx.skip("emcc is not installed (apt-get install emscripten): the rebuild check needs Debian's Emscripten");
      return;
    }
    const r = spawnSync(process.execPath, [`${wasmDir}build.mjs`, '--check'], { encoding: 'utf8', timeout: 1_500_000 });
    const output = `${r.stdout}${r.stderr}`;
    expect(r.status, output).toBe(0);
    expect(output).toMatch(/reproducible: las\.js, las\.wasm, tiff\.js, tiff\.wasm, zfp\.js, zfp\.wasm, build-info\.json are identical/);
  }, 1_600_000);
});
