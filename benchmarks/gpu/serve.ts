// bench:gpu's stores served over HTTP on localhost, as the dev server's
// /stores/ middleware serves them (Range requests honoured).
import { createServer } from 'node:http';
import { storesMiddleware } from '../../scripts/vite-stores.ts';

/** Serves `folder` at http://127.0.0.1:PORT/stores/; `base` is that URL, `close` stops the server. */
export async function serveStores(folder: string): Promise<{ base: string; close(): void }> {
  const mw = storesMiddleware(folder);
  const server = createServer((req, res) =>
    mw(req, res, () => {
      res.statusCode = 404;
      res.end();
    }),
  );
  await new Promise<void>((r) => server.listen(0, '127.0.0.1', () => r()));
  return {
    base: `http://127.0.0.1:${(server.address() as { port: number }).port}/stores`,
    close: () => {
      server.closeAllConnections();
      server.close();
    },
  };
}
