// A store behind a misbehaving server (scripts/store-faults.ts: HTTP 500,
// 503 and 429 with Retry-After, dropped connections, bodies cut short, slow
// answers; seeded, independent per attempt, on every kind of request:
// metadata, range arrays, shard indexes, chunks). At 30% faults, `cli
// extract STORE --level 0` writes exactly the fault-free surface (PLY
// byte-equal) for several seeds; at 100% on one shard the error names the
// chunk and the cause; exit codes: 1 for the data or the network, 2 only for
// a wrong command line (and the usage text only then).
import { execFile } from 'node:child_process';
import { mkdirSync, mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { createServer, type Server } from 'node:http';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { afterAll, beforeAll, describe, expect, it } from 'vitest';
import { FaultInjector, faultPrefix } from '../../../scripts/store-faults.ts';
import { storesMiddleware } from '../../../scripts/vite-stores.ts';
import { repoRoot } from '../../helpers/python.ts';
import { convert } from './stores.ts';

const work = mkdtempSync(join(tmpdir(), 'store-faults-'));
const stores = join(work, 'stores');
const faults = new FaultInjector();
let server: Server;
let base = '';

/** The CLI in a child process, asynchronously (the server answers in this one). */
function cli(...args: string[]): Promise<{ status: number; stderr: string }> {
  return new Promise((resolve) => {
    execFile(
      process.execPath,
      ['--import', join(repoRoot, 'scripts/register-node-loaders.mjs'), join(repoRoot, 'src/cli/main.ts'), ...args],
      { encoding: 'utf8', timeout: 600_000, maxBuffer: 1 << 24 },
      (error, _stdout, stderr) => resolve({ status: error ? ((error as { code?: number }).code ?? 1) : 0, stderr }),
    );
  });
}

beforeAll(async () => {
  mkdirSync(stores, { recursive: true });
  convert('volumes/hydrogen_atom_128x128x128_float32.raw', join(stores, 'hydrogen.zarr'), ['--chunk', '16', '--rate', '6', '--shard', '2']);
  const mw = storesMiddleware(stores, faults);
  server = createServer((req, res) =>
    mw(req, res, () => {
      res.statusCode = 404;
      res.end();
    }),
  );
  await new Promise<void>((r) => server.listen(0, '127.0.0.1', () => r()));
  base = `http://127.0.0.1:${(server.address() as { port: number }).port}/stores`;
}, 900_000);
afterAll(() => {
  server.closeAllConnections();
  server.close();
  rmSync(work, { recursive: true, force: true });
});

interface Extracted {
  isosurfaces: { iso: number; triangles: number; vertices: number; surfaceArea: number; ply: string }[];
  store: { retries: number; failedRequests: number; faults: Record<string, number>; chunks: number };
}
const read = (path: string) => JSON.parse(readFileSync(path, 'utf8')) as Extracted;

describe('a store behind a misbehaving server', () => {
  it('30% of requests failing every way: exactly the fault-free surface, for several seeds', async () => {
    const ref = await cli(
      'extract',
      `${base}/hydrogen.zarr`,
      '--level',
      '0',
      '--iso',
      '20,120',
      '--ply',
      join(work, 'ref'),
      '--json',
      join(work, 'ref.json'),
    );
    expect(ref.status, ref.stderr).toBe(0);
    const clean = read(join(work, 'ref.json'));
    expect(clean.store.retries).toBe(0);
    expect(clean.isosurfaces[0].triangles).toBeGreaterThan(10_000);
    for (const seed of [1, 2, 3]) {
      const url = `${base}/${faultPrefix({ rate: 0.3, seed })}/hydrogen.zarr`;
      const r = await cli(
        'extract',
        url,
        '--level',
        '0',
        '--iso',
        '20,120',
        '--ply',
        join(work, `s${seed}`),
        '--json',
        join(work, `s${seed}.json`),
      );
      expect(r.status, r.stderr).toBe(0);
      const got = read(join(work, `s${seed}.json`));
      expect(got.store.retries).toBeGreaterThan(20);
      expect(got.store.failedRequests).toBe(0);
      expect(got.store.chunks).toBe(clean.store.chunks);
      for (const [i, s] of got.isosurfaces.entries()) {
        expect(s.triangles).toBe(clean.isosurfaces[i].triangles);
        expect(readFileSync(s.ply).equals(readFileSync(clean.isosurfaces[i].ply))).toBe(true);
      }
    }
    // every kind of fault, and every kind of request, was hit
    for (const kind of ['500', '503', '429', 'drop', 'truncate', 'slow']) expect(faults.injected[kind]).toBeGreaterThan(3);
    for (const what of ['metadata', 'ranges', 'shard index', 'chunk'] as const) expect(faults.injectedOn[what]).toBeGreaterThan(0);
  }, 600_000);

  it('100% on one shard: the error names the chunk and the cause; exit 1 without the usage', async () => {
    const url = `${base}/${faultPrefix({ rate: 1, seed: 1, kinds: ['503'], match: 'hydrogen.zarr/0/c/2/2/2' })}/hydrogen.zarr`;
    const r = await cli('extract', url, '--level', '0', '--iso', '20', '--deadline', '2', '--json', join(work, 'one.json'));
    expect(r.status).toBe(1);
    expect(r.stderr).not.toMatch(/usage:/);
    expect(r.stderr).toMatch(
      /hydrogen\.zarr level 0 chunk \([45], [45], [45]\): GET \/0\/c\/2\/2\/2 \(last \d+ bytes\): HTTP 503 Service Unavailable \(Retry-After 1 s\), \d tries over \d\.\d s/,
    );
    const rec = JSON.parse(readFileSync(join(work, 'one.json'), 'utf8'));
    expect(rec.isosurfaces[0].error).toMatch(/chunk \([45], [45], [45]\)/);
    expect(rec.store.failedRequests).toBeGreaterThan(0);
  }, 300_000);

  it('exit codes: 2 for a wrong command line (with the usage), 1 for a store that cannot be read (without)', async () => {
    const level = await cli('extract', `${base}/hydrogen.zarr`, '--level', '9', '--iso', '20');
    expect(level.status).toBe(2);
    expect(level.stderr).toMatch(/--level 9 does not exist \(levels 0 to \d\)[\s\S]*usage:/);
    const none = await cli('extract', `${base}/none.zarr`, '--iso', '20');
    expect(none.status).toBe(1);
    expect(none.stderr).toMatch(/none\.zarr: no zarr\.json, \.zgroup or \.zarray at its root/);
    expect(none.stderr).not.toMatch(/usage:/);
    const forbidden = await cli('extract', `${base}/${faultPrefix({ rate: 1, seed: 1, kinds: ['403'] })}/hydrogen.zarr`, '--iso', '20');
    expect(forbidden.status).toBe(1);
    expect(forbidden.stderr).toMatch(/hydrogen\.zarr: GET \/zarr\.json: HTTP 403 Forbidden/);
  }, 300_000);
});
