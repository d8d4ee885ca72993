// The coarsest level read whole at open (src/store/level-values.ts, issue
// 37): its value range and block ranges come from the chunks decoded on the
// CPU. Truth from outside: the converter's range arrays (computed from
// zfpy's decode of each chunk) for a zfp store, and numpy's min/max for a
// store of lossless chunks written by zarr-python.
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, it } from 'vitest';
import { LEVEL_VALUES_LIMITS, readLevelValues } from '../../../src/store/level-values.ts';
import { storeForLocation } from '../../../src/store/zarr/node-store.ts';
import { openStore } from '../../../src/store/zarr/open-store.ts';
import { convert, converterPython, zarrPythonStore } from './stores.ts';

const work = mkdtempSync(join(tmpdir(), 'level-values-'));
const zfpStore = join(work, 'gen.zarr');
beforeAll(() => {
  convert('gen:72x64x40', zfpStore, ['--chunk', '16', '--rate', '6']);
}, 600_000);
afterAll(() => rmSync(work, { recursive: true, force: true }));

/** [min, max] over chunks' [min, max] pairs. */
function span(ranges: Float32Array): [number, number] {
  let lo = Infinity;
  let hi = -Infinity;
  for (let i = 0; i < ranges.length; i += 2) {
    lo = Math.min(lo, ranges[i]);
    hi = Math.max(hi, ranges[i + 1]);
  }
  return [lo, hi];
}

describe('readLevelValues', () => {
  it("a zfp store's levels: the range and each chunk's blocks equal the converter's range arrays (zfpy's decode)", async () => {
    const store = await openStore(storeForLocation(zfpStore), zfpStore);
    for (let L = 0; L < store.levels.length; L++) {
      const lv = store.levels[L];
      const got = await readLevelValues(store, L);
      if (lv.chunkCount > LEVEL_VALUES_LIMITS.maxChunks) {
        expect(got).toBeNull();
        continue;
      }
      const ranges = (await store.readRanges(L))!;
      expect(got!.valueRange).toEqual(span(ranges));
      // per chunk: the [min, max] of its blocks inside the level is the range array's entry
      const { dims, chunkEdge: C, chunkGrid: g } = lv.layout;
      const bg = dims.map((n) => Math.ceil(n / 4));
      for (let c = 0; c < lv.chunkCount; c++) {
        const at = [c % g[0], Math.floor(c / g[0]) % g[1], Math.floor(c / (g[0] * g[1]))];
        let lo = Infinity;
        let hi = -Infinity;
        for (let z = (at[2] * C) / 4; z < Math.min(bg[2], ((at[2] + 1) * C) / 4); z++)
          for (let y = (at[1] * C) / 4; y < Math.min(bg[1], ((at[1] + 1) * C) / 4); y++)
            for (let x = (at[0] * C) / 4; x < Math.min(bg[0], ((at[0] + 1) * C) / 4); x++) {
              const b = x + bg[0] * (y + bg[1] * z);
              lo = Math.min(lo, got!.blockRanges[2 * b]);
              hi = Math.max(hi, got!.blockRanges[2 * b + 1]);
            }
        expect([lo, hi], `level ${L} chunk ${c}`).toEqual([ranges[2 * c], ranges[2 * c + 1]]);
      }
    }
    store.close?.();
  });

  it('a store of lossless chunks (zarr-python, zstd, partial edge chunks): the range is numpy min/max of the values as float32', async () => {
    const path = zarrPythonStore(join(work, 'zstd.zarr'), [20, 30, 45], 16, 'compressors=zarr.codecs.ZstdCodec()', 'int16');
    // zarrPythonStore's field as int16, and numpy's min/max of it
    const [lo, hi] = converterPython(
      `
import sys, numpy as np, zarr
a = zarr.open_array(sys.argv[1], mode='r')[...]
print(float(a.min()), float(a.max()))
`,
      [path],
    )
      .trim()
      .split(' ')
      .map(Number);
    expect(hi).toBeGreaterThan(lo);
    const store = await openStore(storeForLocation(path), path, { rate: 8 });
    const got = await readLevelValues(store, store.levels.length - 1);
    expect(got!.valueRange).toEqual([lo, hi]);
    expect(got!.dims).toEqual([45, 30, 20]);
    store.close?.();
  });
});
