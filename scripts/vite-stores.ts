// The dev and preview servers serve a local folder of Zarr stores at
// /stores/ (ZFPISO_STORES, default test-results/stores, which the tests
// fill), the way a static host or object store serves them to the page:
// HTTP Range requests (206 with Content-Range; zarrita reads shard indexes
// and inner chunks with them), HEAD, and CORS headers (a page on another
// origin may read the store, including the Range header and the lengths).
// A /stores/~faults(...)/ prefix serves the same stores through a
// misbehaving server (store-faults.ts), for the tests and benchmarks.
// /stores/~log is the server's log of the store requests it received (the
// last 10,000: when, method and path), for the page tests.
import { createReadStream, existsSync, statSync } from 'node:fs';
import type { IncomingMessage, ServerResponse } from 'node:http';
import { join, normalize, resolve, sep } from 'node:path';
import type { Plugin } from 'vite';
import { FaultInjector, parseFaultPrefix } from './store-faults.ts';

export const STORES_PREFIX = '/stores/';

export function defaultStoresFolder(): string {
  return resolve(process.env.ZFPISO_STORES ?? 'test-results/stores');
}

/** [start, end] inclusive, or null for a malformed / unsatisfiable range. */
export function parseRange(header: string, size: number): [number, number] | null {
  const m = /^bytes=(\d*)-(\d*)$/.exec(header.trim());
  if (!m || (m[1] === '' && m[2] === '')) return null;
  if (m[1] === '') {
    const n = Number(m[2]);
    if (n === 0) return null;
    return [Math.max(0, size - n), size - 1];
  }
  const start = Number(m[1]);
  const end = m[2] === '' ? size - 1 : Math.min(Number(m[2]), size - 1);
  if (start >= size || end < start) return null;
  return [start, end];
}

/** A store request the server received: ms since the server started, method, the path under /stores/. */
export interface LoggedRequest {
  ms: number;
  method: string;
  path: string;
}
const LOG_KEPT = 10_000;

export function storesMiddleware(folder = defaultStoresFolder(), faults = new FaultInjector()) {
  const root = resolve(folder);
  const log: LoggedRequest[] = [];
  const t0 = performance.now();
  return (req: IncomingMessage, res: ServerResponse, next: () => void) => {
    const url = req.url ?? '';
    if (!url.startsWith(STORES_PREFIX)) return next();
    if (url.startsWith(`${STORES_PREFIX}~log`)) {
      res.setHeader('Content-Type', 'application/json');
      res.setHeader('Cache-Control', 'no-store');
      res.end(JSON.stringify({ now: performance.now() - t0, requests: log }));
      return;
    }
    log.push({ ms: performance.now() - t0, method: req.method ?? 'GET', path: url.slice(STORES_PREFIX.length) });
    if (log.length > LOG_KEPT) log.splice(0, log.length - LOG_KEPT);
    res.setHeader('Access-Control-Allow-Origin', '*');
    res.setHeader('Access-Control-Allow-Headers', 'Range');
    res.setHeader('Access-Control-Expose-Headers', 'Content-Length, Content-Range, Accept-Ranges');
    if (req.method === 'OPTIONS') {
      res.statusCode = 204;
      res.end();
      return;
    }
    if (req.method !== 'GET' && req.method !== 'HEAD') {
      res.statusCode = 405;
      res.end();
      return;
    }
    let rel: string;
    try {
      rel = decodeURIComponent(url.slice(STORES_PREFIX.length).split('?')[0]);
    } catch {
      res.statusCode = 400;
      res.end();
      return;
    }
    const faulty = parseFaultPrefix(rel);
    if (faulty) rel = faulty.rest;
    const path = normalize(join(root, rel));
    if (!path.startsWith(root + sep) || !existsSync(path) || !statSync(path).isFile()) {
      res.statusCode = 404;
      res.end('not found');
      return;
    }
    const size = statSync(path).size;
    res.setHeader('Accept-Ranges', 'bytes');
    res.setHeader('Content-Type', path.endsWith('.json') ? 'application/json' : 'application/octet-stream');
    res.setHeader('Cache-Control', 'no-cache');
    let start = 0;
    let end = size - 1;
    const range = req.headers.range;
    if (range) {
      const r = parseRange(range, size);
      if (!r) {
        res.statusCode = 416;
        res.setHeader('Content-Range', `bytes */${size}`);
        res.end();
        return;
      }
      [start, end] = r;
      res.statusCode = 206;
      res.setHeader('Content-Range', `bytes ${start}-${end}/${size}`);
    }
    const serve = (cut?: number) => {
      res.setHeader('Content-Length', String(end - start + 1));
      if (req.method === 'HEAD' || size === 0) {
        res.end();
        return;
      }
      if (cut === undefined) {
        createReadStream(path, { start, end }).pipe(res);
        return;
      }
      // the headers promise the whole body; the connection drops halfway
      const stop = start + Math.floor((end - start + 1) * cut);
      if (stop <= start) {
        res.flushHeaders();
        setImmediate(() => req.socket.destroy());
        return;
      }
      const part = createReadStream(path, { start, end: stop - 1 });
      part.on('data', (b) => res.write(b));
      part.on('end', () => setImmediate(() => req.socket.destroy()));
    };
    const fault = faulty ? faults.decide(faulty.spec, req.method ?? 'GET', rel, range) : null;
    if (fault) faults.apply(fault, req, res, serve);
    else serve();
  };
}

export function storesPlugin(folder?: string): Plugin {
  return {
    name: 'zfpiso-stores',
    configureServer(server) {
      server.middlewares.use(storesMiddleware(folder));
    },
    configurePreviewServer(server) {
      server.middlewares.use(storesMiddleware(folder));
    },
  };
}
