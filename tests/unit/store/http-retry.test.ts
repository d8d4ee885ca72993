// HttpStore + RetryingStore against a scripted HTTP server: each way a
// request fails is named from what was observed (status and Retry-After, a
// connection dropped before the answer, a body cut short of its
// Content-Length, a timed-out attempt, a Range ignored), transient failures
// are tried again until the per-request deadline (Retry-After honoured),
// permanent ones fail at once, 404 is a missing key, and an abort stops the
// waiting at once.
import { createServer, type IncomingMessage, type Server, type ServerResponse } from 'node:http';
import { afterAll, beforeAll, describe, expect, it } from 'vitest';
import { RequestFailedError, TransportError } from '../../../src/store/zarr/errors.ts';
import { HttpStore, parseRetryAfter } from '../../../src/store/zarr/http-store.ts';
import { RetryingStore } from '../../../src/store/zarr/retrying-store.ts';

type Script = (req: IncomingMessage, res: ServerResponse, attempt: number) => void;
const scripts = new Map<string, Script>();
const attempts = new Map<string, number>();
const BODY = new Uint8Array(1000).map((_, i) => (i * 7) & 255);
let server: Server;
let base = '';

function ok(res: ServerResponse, body = BODY): void {
  res.setHeader('Content-Length', String(body.length));
  res.end(Buffer.from(body));
}

beforeAll(async () => {
  server = createServer((req, res) => {
    const path = req.url ?? '';
    const n = (attempts.get(path) ?? 0) + 1;
    attempts.set(path, n);
    const script = scripts.get(path);
    if (!script) {
      res.statusCode = 404;
      res.end();
      return;
    }
    script(req, res, n);
  });
  await new Promise<void>((r) => server.listen(0, '127.0.0.1', () => r()));
  base = `http://127.0.0.1:${(server.address() as { port: number }).port}/s.zarr`;
});
afterAll(() => {
  server.closeAllConnections();
  server.close();
});

/** The store under test: short waits, a deadline of `deadlineMs`. */
function store(deadlineMs = 3000, attemptTimeoutMs = 2000) {
  return new RetryingStore(new HttpStore(base, { attemptTimeoutMs }), { deadlineMs, firstDelayMs: 20, maxDelayMs: 100 });
}

async function failure(p: Promise<unknown>): Promise<RequestFailedError> {
  try {
    await p;
  } catch (e) {
    expect(e).toBeInstanceOf(RequestFailedError);
    return e as RequestFailedError;
  }
  throw new Error('expected a failure');
}

describe('HttpStore + RetryingStore', () => {
  it('HTTP 500 then success: retried, the bytes exact', async () => {
    scripts.set('/s.zarr/a', (_q, res, n) => {
      if (n <= 2) {
        res.statusCode = 500;
        res.end();
      } else ok(res);
    });
    const s = store();
    expect(await s.get('/a')).toEqual(BODY);
    expect(attempts.get('/s.zarr/a')).toBe(3);
    expect(s.counters).toMatchObject({ retries: 2, failed: 0, faults: { 'HTTP 500': 2 } });
  });

  it('503 with Retry-After is waited for; past the deadline it fails naming the status and the tries', async () => {
    scripts.set('/s.zarr/b', (_q, res, n) => {
      if (n === 1) {
        res.statusCode = 503;
        res.setHeader('Retry-After', '1');
        res.end();
      } else ok(res);
    });
    const t0 = performance.now();
    expect(await store().get('/b')).toEqual(BODY);
    expect(performance.now() - t0).toBeGreaterThanOrEqual(950);
    scripts.set('/s.zarr/c', (_q, res) => {
      res.statusCode = 503;
      res.statusMessage = 'Slow Down';
      res.end();
    });
    const t1 = performance.now();
    const e = await failure(store(600).get('/c'));
    expect(performance.now() - t1).toBeLessThan(1500);
    expect(e.message).toMatch(/^GET \/c: HTTP 503 Slow Down, \d+ tries over 0\.\d s$/);
    expect(e.kind).toBe('http');
    // a Retry-After beyond the deadline ends the request at once, saying so
    scripts.set('/s.zarr/d', (_q, res) => {
      res.statusCode = 429;
      res.setHeader('Retry-After', '60');
      res.end();
    });
    const e2 = await failure(store(5000).get('/d'));
    expect(e2.message).toMatch(/HTTP 429 .*Retry-After 60 s.*the server asks to wait 60 s, past the 5 s deadline/);
    expect(attempts.get('/s.zarr/d')).toBe(1);
  });

  it('a body cut short of its Content-Length and a dropped connection are retried, and named when they persist', async () => {
    scripts.set('/s.zarr/e', (req, res, n) => {
      if (n === 1) {
        res.setHeader('Content-Length', String(BODY.length));
        res.write(Buffer.from(BODY.subarray(0, 300)));
        setTimeout(() => req.socket.destroy(), 20);
      } else if (n === 2) req.socket.destroy();
      else ok(res);
    });
    const s = store();
    expect(await s.get('/e')).toEqual(BODY);
    expect(s.counters.faults).toMatchObject({ truncated: 1, dropped: 1 });
    scripts.set('/s.zarr/f', (req, res) => {
      res.setHeader('Content-Length', String(BODY.length));
      res.write(Buffer.from(BODY.subarray(0, 300)));
      setTimeout(() => req.socket.destroy(), 20);
    });
    const e = await failure(store(400).get('/f'));
    expect(e.message).toMatch(/^GET \/f: the (connection dropped after 300 of 1000 bytes of the body|body ended after 300 of 1000 bytes)/);
    expect(e.kind).toBe('network');
  });

  it('an attempt that hangs times out and is tried again', async () => {
    scripts.set('/s.zarr/g', (_q, res, n) => {
      if (n === 1) return; // never answers
      ok(res);
    });
    const s = store(3000, 300);
    expect(await s.get('/g')).toEqual(BODY);
    expect(s.counters.faults).toMatchObject({ timeout: 1 });
    scripts.set('/s.zarr/h', () => {});
    const e = await failure(store(700, 200).get('/h'));
    expect(e.message).toMatch(/^GET \/h: timed out after 0\.2 s, \d+ tries over 0\.\d s$/);
  });

  it('permanent answers fail at once: 403, a Range ignored, a 206 of the wrong length; 404 is a missing key', async () => {
    scripts.set('/s.zarr/i', (_q, res) => {
      res.statusCode = 403;
      res.statusMessage = 'Forbidden';
      res.end();
    });
    const e = await failure(store().get('/i'));
    expect(e.message).toBe('GET /i: HTTP 403 Forbidden');
    expect(attempts.get('/s.zarr/i')).toBe(1);
    scripts.set('/s.zarr/j', (_q, res) => ok(res)); // ignores Range
    const r = await failure(store().getRange('/j', { offset: 10, length: 20 }));
    expect(r.message).toMatch(/^GET \/j \(bytes 10-29\): the server ignored the Range header \(HTTP 200 with the whole file/);
    expect(attempts.get('/s.zarr/j')).toBe(1);
    scripts.set('/s.zarr/k', (req, res) => {
      expect(req.headers.range).toBe('bytes=-16');
      res.statusCode = 206;
      ok(res, BODY.subarray(BODY.length - 16));
    });
    expect(await store().getRange('/k', { suffixLength: 16 })).toEqual(BODY.subarray(BODY.length - 16));
    scripts.set('/s.zarr/l', (_q, res) => {
      res.statusCode = 206;
      ok(res, BODY.subarray(0, 5));
    });
    expect((await failure(store().getRange('/l', { offset: 0, length: 20 }))).message).toMatch(
      /the server answered 5 bytes where the range asked 20/,
    );
    expect(await store().get('/missing')).toBeUndefined();
    expect(attempts.get('/s.zarr/missing')).toBe(1);
  });

  it('an abort stops a request while it waits to try again', async () => {
    scripts.set('/s.zarr/m', (_q, res) => {
      res.statusCode = 503;
      res.setHeader('Retry-After', '5');
      res.end();
    });
    const ctl = new AbortController();
    const p = store(30_000).get('/m', { signal: ctl.signal });
    setTimeout(() => ctl.abort(new DOMException('no longer needed', 'AbortError')), 150);
    const t0 = performance.now();
    await expect(p).rejects.toMatchObject({ name: 'AbortError' });
    expect(performance.now() - t0).toBeLessThan(1000);
  });

  it('Retry-After in seconds or as a date; a TransportError says whether retrying helps', () => {
    expect(parseRetryAfter('3')).toBe(3000);
    expect(parseRetryAfter(new Date(Date.now() + 10_000).toUTCString(), Date.now())).toBeGreaterThan(8000);
    expect(parseRetryAfter('soon')).toBeUndefined();
    expect(new TransportError('http', 'x', true).transient).toBe(true);
  });
});
