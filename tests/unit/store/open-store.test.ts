// Opening stores through zarrita: layouts, chunk bytes exactly as stored
// (plain and sharded), ranges, stores written by zarr-python without our
// attributes, and every refusal naming the store (and level / chunk).
import { mkdtempSync, readFileSync, rmSync, truncateSync, unlinkSync, writeFileSync } from 'node:fs';
import { createServer, type Server } from 'node:http';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { HttpStore } from '../../../src/store/zarr/http-store.ts';
import { afterAll, beforeAll, describe, expect, it } from 'vitest';
import { StoreError } from '../../../src/store/zarr/errors.ts';
import { storeForLocation } from '../../../src/store/zarr/node-store.ts';
import { openStore, type ZfpStore } from '../../../src/store/zarr/open-store.ts';
import { converterPython, convert, zarrPythonStore } from './stores.ts';

const work = mkdtempSync(join(tmpdir(), 'store-open-'));
const plain = join(work, 'neghip.zarr');
const sharded = join(work, 'neghip-shard.zarr');
const open = async (path: string) => openStore(storeForLocation(path), path);

async function refusal(p: Promise<unknown>): Promise<StoreError> {
  const e = await p.then(
    () => null,
    (x: unknown) => x,
  );
  expect(e).toBeInstanceOf(StoreError);
  return e as StoreError;
}

beforeAll(() => {
  convert('volumes/neghip_66x66x66_uint8.raw', plain, ['--chunk', '16', '--rate', '8,6']);
  convert('volumes/neghip_66x66x66_uint8.raw', sharded, ['--chunk', '16', '--rate', '8,6', '--shard', '2']);
}, 900_000);
afterAll(() => rmSync(work, { recursive: true, force: true }));

describe('openStore', () => {
  it('reads the levels of a converted store and every chunk as stored', async () => {
    const s = await open(plain);
    expect(s.levels.map((l) => l.layout.dims)).toEqual([
      [66, 66, 66],
      [33, 33, 33],
      [17, 17, 17],
      [9, 9, 9],
    ]);
    expect(s.levels.map((l) => l.layout.chunkGrid)).toEqual([
      [5, 5, 5],
      [3, 3, 3],
      [2, 2, 2],
      [1, 1, 1],
    ]);
    expect(s.levels.map((l) => l.layout.rate)).toEqual([8, 6, 6, 6]);
    // zfpy's stream: 12-byte header + 64 blocks x 64 R bits, padded to 8 bytes
    expect(s.levels[0].layout.chunkBytes).toBe(12 + 64 * 8 * 8 + 4);
    expect(s.levels[1].layout.chunkBytes).toBe(readFileSync(join(plain, '1/c/0/0/0')).length);
    expect(s.notes).toEqual([]);
    for (const chunk of [0, 7, 124]) {
      const [x, y, z] = [chunk % 5, Math.floor(chunk / 5) % 5, Math.floor(chunk / 25)];
      expect(Buffer.from(await s.readChunk(0, chunk)).equals(readFileSync(join(plain, `0/c/${z}/${y}/${x}`)))).toBe(true);
    }
    // ranges/<L> against zarr-python's reading of the same array
    const ref = JSON.parse(
      converterPython(
        `
import sys, json, zarr
print(json.dumps(zarr.open_array(sys.argv[1], mode='r', path='ranges/1')[:].reshape(-1).tolist()))`,
        [plain],
      ),
    ) as number[];
    expect(Array.from((await s.readRanges(1))!)).toEqual(ref);
  });

  it('reads inner chunks of shards (zarrita reads the index) with the same bytes', async () => {
    const a = await open(plain);
    const b = await open(sharded);
    expect(b.levels[0].shardChunks).toBe(2);
    for (const chunk of [0, 1, 31, 124])
      expect(Buffer.from(await b.readChunk(0, chunk)).equals(Buffer.from(await a.readChunk(0, chunk)))).toBe(true);
    expect(await b.readRanges(0)).toEqual(await a.readRanges(0));
  });

  it('opens a zfpy fixed-rate array written by zarr-python, without ranges', async () => {
    const other = zarrPythonStore(join(work, 'other.zarr'), [20, 24, 36], 8, 'serializer=ZFPY(mode=2, rate=8), compressors=None');
    const s = await open(other);
    expect(s.levels).toHaveLength(1);
    expect(s.levels[0].layout).toMatchObject({
      dims: [36, 24, 20],
      chunkEdge: 8,
      chunkGrid: [5, 3, 3],
      rate: 8,
      chunkBytes: 12 + 8 * 64 + 4,
    });
    expect(await s.readRanges(0)).toBeNull();
    expect(s.notes.join()).toMatch(/no per-chunk range arrays/);
    expect((await s.readChunk(0, 44)).length).toBe(s.levels[0].layout.chunkBytes);
  });

  it('refuses other codecs, modes, types and chunk edges, saying how to convert', async () => {
    const gzip = zarrPythonStore(join(work, 'gzip.zarr'), [8, 8, 8], 8, 'compressors=zarr.codecs.GzipCodec()');
    // lossless chunks are not refused: they are read as a store compressed on the GPU (source-store.test.ts)
    const lossless = await open(gzip);
    expect(lossless.source?.codecs).toEqual(['bytes', 'gzip']);
    expect(lossless.levels[0].layout.arrivesAs).toBe('float32');
    const acc = zarrPythonStore(join(work, 'acc.zarr'), [8, 8, 8], 8, 'serializer=ZFPY(mode=4, tolerance=0.01), compressors=None');
    expect((await refusal(open(acc))).message).toMatch(/acc.zarr level 0: numcodecs.zfpy in fixed accuracy mode/);
    const edge = zarrPythonStore(join(work, 'edge.zarr'), [12, 12, 12], 6, 'serializer=ZFPY(mode=2, rate=8), compressors=None');
    expect((await refusal(open(edge))).message).toMatch(/edge.zarr level 0: chunk edge 6 is not a multiple of 4/);
    const f64 = zarrPythonStore(join(work, 'f64.zarr'), [8, 8, 8], 8, 'serializer=ZFPY(mode=2, rate=8), compressors=None', 'float64');
    expect((await refusal(open(f64))).message).toMatch(/f64.zarr level 0: values are float64/);
  });

  it('refuses hostile sizes in the metadata before allocating anything', async () => {
    const huge = zarrPythonStore(join(work, 'huge.zarr'), [8, 8, 8], 8, 'serializer=ZFPY(mode=2, rate=8), compressors=None');
    const meta = JSON.parse(readFileSync(join(huge, 'zarr.json'), 'utf8'));
    meta.shape = [1e9, 1e9, 1e9];
    writeFileSync(join(huge, 'zarr.json'), JSON.stringify(meta));
    expect((await refusal(open(huge))).message).toMatch(
      /huge.zarr level 0: 125000000 x 125000000 x 125000000 chunks of 8\^3; this reader takes at most 67108864 per level/,
    );
    meta.shape = [8, 8, 2 ** 32];
    writeFileSync(join(huge, 'zarr.json'), JSON.stringify(meta));
    expect((await refusal(open(huge))).message).toMatch(/huge.zarr level 0: shape \[8, 8, 4294967296\] is not a volume this reader takes/);
  });

  it('refuses a missing folder and a corrupt chunk, naming them; an absent chunk is the fill value', async () => {
    expect((await refusal(open(join(work, 'nothing.zarr')))).message).toMatch(/nothing.zarr: no such folder/);
    const s: ZfpStore = await open(plain);
    unlinkSync(join(plain, '0/c/0/0/1'));
    // absent: the array's fill value (0), the stream zfpy writes for a constant chunk
    const zeros = converterPython(
      'import sys, zfpy, numpy as np; sys.stdout.write(zfpy.compress_numpy(np.zeros((16, 16, 16), np.float32), rate=8, write_header=True).hex())',
    );
    expect(Buffer.from(await s.readChunk(0, 1)).toString('hex')).toBe(zeros);
    truncateSync(join(plain, '0/c/0/1/0'), 100);
    expect((await refusal(s.readChunk(0, 5))).message).toMatch(/level 0 chunk \(0, 1, 0\): 100 bytes, .* has 4112/);
    const bytes = readFileSync(join(plain, '0/c/1/0/0'));
    bytes[0] = 0x41;
    writeFileSync(join(plain, '0/c/1/0/0'), bytes);
    expect((await refusal(s.readChunk(0, 25))).message).toMatch(/chunk \(0, 0, 1\): not a zfp stream \(wrong magic/);
    // a damaged shard index (zarrita does not check its crc32c): the inner
    // chunk it now points at fails our size check. Chunk (1, 1, 1) is the
    // shard's last index entry; its nbytes sit 12 to 4 bytes from the end.
    const shard = join(sharded, '0/c/0/0/0');
    const sb = readFileSync(shard);
    sb[sb.length - 10] ^= 0xff;
    writeFileSync(shard, sb);
    const t = await open(sharded);
    expect((await refusal(t.readChunk(0, 31))).message).toMatch(/neghip-shard.zarr level 0 chunk \(1, 1, 1\): \d+ bytes/);
  });

  describe('over HTTP (HttpStore)', () => {
    let server: Server;
    let base = '';
    beforeAll(async () => {
      server = createServer((req, res) => {
        if (req.url?.startsWith('/forbidden/')) {
          res.statusCode = 403;
          res.end();
          return;
        }
        res.statusCode = 404;
        res.end();
      });
      await new Promise<void>((r) => server.listen(0, '127.0.0.1', () => r()));
      const addr = server.address();
      base = `http://127.0.0.1:${typeof addr === 'object' && addr ? addr.port : 0}`;
    });
    afterAll(() => server.close());

    it('404, HTTP errors and an unreachable host are messages naming the store and what was observed', async () => {
      const url404 = `${base}/none.zarr`;
      expect((await refusal(openStore(new HttpStore(url404), url404))).message).toMatch(
        /none.zarr: no zarr.json, .zgroup or .zarray at its root/,
      );
      const url403 = `${base}/forbidden/a.zarr`;
      // a 403 is an answer: refused at once, not retried
      const forbidden = await refusal(openStore(new HttpStore(url403), url403));
      expect(forbidden.message).toMatch(/a.zarr: GET \/zarr.json: HTTP 403 Forbidden$/);
      // a port nothing listens on: a host that never answered gets a few quick tries, then the cause
      const gone = createServer();
      await new Promise<void>((r) => gone.listen(0, '127.0.0.1', () => r()));
      const port = (gone.address() as { port: number }).port;
      await new Promise<void>((r) => gone.close(() => r()));
      const closed = `http://127.0.0.1:${port}/x.zarr`;
      const e = await refusal(openStore(new HttpStore(closed), closed, { retry: { firstDelayMs: 1 } }));
      expect(e.message).toMatch(/x.zarr: GET \/zarr.json: the connection was refused .*, 3 tries over/);
    });
  });
});
