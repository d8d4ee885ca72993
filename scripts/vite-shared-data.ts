// Dev/test convenience: the Vite dev and preview servers serve the shared
// test data folder (../shared/data, next to the repository) at /data/, so
// the page can open e.g. /?url=/data/volumes/hydrogen_atom_128x128x128_float32.rate8.zfp.
// Nothing is copied into the repository or the build; without the folder the
// plugin does nothing.
import { createReadStream, existsSync, statSync } from 'node:fs';
import type { IncomingMessage, ServerResponse } from 'node:http';
import { join, normalize, resolve, sep } from 'node:path';
import { fileURLToPath } from 'node:url';
import type { Plugin } from 'vite';

export const SHARED_DATA_PREFIX = '/data/';

export function sharedDataPlugin(folder = fileURLToPath(new URL('../../shared/data', import.meta.url))): Plugin {
  const root = resolve(folder);
  const serve = (req: IncomingMessage, res: ServerResponse, next: () => void) => {
    const url = req.url ?? '';
    if (!url.startsWith(SHARED_DATA_PREFIX) || (req.method !== 'GET' && req.method !== 'HEAD')) return next();
    let rel: string;
    try {
      rel = decodeURIComponent(url.slice(SHARED_DATA_PREFIX.length).split('?')[0]);
    } catch {
      return next();
    }
    const path = normalize(join(root, rel));
    if (!path.startsWith(root + sep) || !existsSync(path) || !statSync(path).isFile()) {
      res.statusCode = 404;
      res.end('not found');
      return;
    }
    res.setHeader('Content-Type', 'application/octet-stream');
    res.setHeader('Content-Length', String(statSync(path).size));
    res.setHeader('Cache-Control', 'no-cache');
    if (req.method === 'HEAD') return res.end();
    createReadStream(path).pipe(res);
  };
  return {
    name: 'zfpiso-shared-data',
    configureServer(server) {
      if (existsSync(root)) server.middlewares.use(serve);
    },
    configurePreviewServer(server) {
      if (existsSync(root)) server.middlewares.use(serve);
    },
  };
}
