// The dev/preview servers' /stores/ middleware, on a real HTTP server: a
// sharded store opened through our HttpStore (shard index by a suffix range,
// inner chunks by byte ranges) and through zarrita's FetchStore (a HEAD, then
// ranges) gives the same chunks as the folder; CORS preflight and headers;
// malformed and unsatisfiable ranges.
import { mkdirSync, mkdtempSync, rmSync } from 'node:fs';
import { createServer, type Server } from 'node:http';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { FetchStore } from 'zarrita';
import { afterAll, beforeAll, describe, expect, it } from 'vitest';
import { parseRange, storesMiddleware } from '../../../scripts/vite-stores.ts';
import { HttpStore } from '../../../src/store/zarr/http-store.ts';
import { storeForLocation } from '../../../src/store/zarr/node-store.ts';
import { openStore } from '../../../src/store/zarr/open-store.ts';
import { convert } from './stores.ts';

const work = mkdtempSync(join(tmpdir(), 'store-serve-'));
let server: Server;
let base = '';

beforeAll(async () => {
  mkdirSync(join(work, 'stores'));
  convert('volumes/neghip_66x66x66_uint8.raw', join(work, 'stores/neghip.zarr'), ['--chunk', '16', '--rate', '8', '--shard', '2']);
  const mw = storesMiddleware(join(work, 'stores'));
  server = createServer((req, res) =>
    mw(req, res, () => {
      res.statusCode = 418;
      res.end();
    }),
  );
  await new Promise<void>((r) => server.listen(0, '127.0.0.1', () => r()));
  const a = server.address();
  base = `http://127.0.0.1:${typeof a === 'object' && a ? a.port : 0}`;
}, 900_000);
afterAll(() => {
  server.close();
  rmSync(work, { recursive: true, force: true });
});

describe('/stores/ on the dev and preview servers', () => {
  it('serves a sharded store to zarrita with the same chunk bytes as the folder', async () => {
    const url = `${base}/stores/neghip.zarr`;
    const disk = await openStore(storeForLocation(join(work, 'stores/neghip.zarr')), 'disk');
    for (const http of [await openStore(new HttpStore(url), url), await openStore(new FetchStore(url), url)]) {
      expect(http.levels.map((l) => l.layout.dims)).toEqual(disk.levels.map((l) => l.layout.dims));
      for (const c of [0, 31, 62, 124])
        expect(Buffer.from(await http.readChunk(0, c)).equals(Buffer.from(await disk.readChunk(0, c)))).toBe(true);
      expect(await http.readRanges(0)).toEqual(await disk.readRanges(0));
    }
  });

  it('answers CORS preflights and ranges, refuses bad ones', async () => {
    const pre = await fetch(`${base}/stores/neghip.zarr/zarr.json`, { method: 'OPTIONS' });
    expect(pre.status).toBe(204);
    expect(pre.headers.get('access-control-allow-origin')).toBe('*');
    expect(pre.headers.get('access-control-allow-headers')).toMatch(/Range/);
    const r = await fetch(`${base}/stores/neghip.zarr/zarr.json`, { headers: { Range: 'bytes=2-5' } });
    expect(r.status).toBe(206);
    expect(r.headers.get('content-range')).toMatch(/^bytes 2-5\/\d+$/);
    expect((await r.arrayBuffer()).byteLength).toBe(4);
    expect((await fetch(`${base}/stores/neghip.zarr/zarr.json`, { headers: { Range: 'bytes=999999-' } })).status).toBe(416);
    expect((await fetch(`${base}/stores/none.zarr/zarr.json`)).status).toBe(404);
    expect((await fetch(`${base}/stores/../package.json`)).status).not.toBe(200);
    expect(parseRange('bytes=-10', 100)).toEqual([90, 99]);
    expect(parseRange('bytes=5-', 100)).toEqual([5, 99]);
    expect(parseRange('bytes=5-500', 100)).toEqual([5, 99]);
    expect(parseRange('items=1-2', 100)).toBeNull();
  });
});
