// Level 0 assembled from its chunks is, byte for byte, what zfpy writes when
// it compresses the whole input volume as one stream at the same rate: the
// converter's promise that chunk blocks are the whole volume's blocks, and
// the reference the streaming path is held to. Partial chunks at the far
// edges, a partial 4^3 block (66 = 16 x 4 + 2), and a rate whose blocks are
// not a whole number of bytes (bit-level copies).
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, describe, expect, it } from 'vitest';
import { assembleLevelStream } from '../../../src/store/assemble.ts';
import { storeForLocation } from '../../../src/store/zarr/node-store.ts';
import { openStore } from '../../../src/store/zarr/open-store.ts';
import { sharedData } from '../../helpers/python.ts';
import { convert, converterPython } from './stores.ts';

const work = mkdtempSync(join(tmpdir(), 'store-assemble-'));
afterAll(() => rmSync(work, { recursive: true, force: true }));

describe('assembleLevelStream', () => {
  it.each([
    ['8', 16],
    ['4.5', 32],
    ['1.4', 16],
  ])('rate %s, chunk %i: level 0 equals zfpy on the whole input', async (rate, chunk) => {
    const path = join(work, `neghip-${rate}-${chunk}.zarr`);
    convert('volumes/neghip_66x66x66_uint8.raw', path, ['--chunk', String(chunk), '--rate', rate, '--levels', '2']);
    const s = await openStore(storeForLocation(path), path);
    {
      const level = 0;
      const L = s.levels[level];
      const chunks = await Promise.all(Array.from({ length: L.chunkCount }, (_, i) => s.readChunk(level, i)));
      const ours = assembleLevelStream(L.layout, (i) => chunks[i]);
      const ref = join(work, `ref-${rate}-${chunk}-${level}.zfp`);
      converterPython(
        `
import sys, zfpy, numpy as np
a = np.fromfile(sys.argv[1], dtype=np.uint8).reshape(66, 66, 66).astype(np.float32)
open(sys.argv[4], 'wb').write(zfpy.compress_numpy(np.ascontiguousarray(a), rate=float(sys.argv[3]), write_header=True))
`,
        [join(sharedData, 'volumes/neghip_66x66x66_uint8.raw'), String(level), String(L.layout.rate), ref],
      );
      expect(Buffer.from(ours).equals(readFileSync(ref)), `level ${level}`).toBe(true);
    }
  });
});
