// Reads a dropped/picked file or a same-origin URL into memory, reporting
// progress and honouring cancellation.

export class LoadCancelled extends Error {
  constructor() {
    super('cancelled');
    this.name = 'LoadCancelled';
  }
}

export type ReadProgress = (done: number, total: number | undefined) => void;

async function drain(
  stream: ReadableStream<Uint8Array>,
  total: number | undefined,
  onProgress: ReadProgress,
  signal: AbortSignal,
): Promise<Uint8Array> {
  const reader = stream.getReader();
  const chunks: Uint8Array[] = [];
  let done = 0;
  let out = total !== undefined ? new Uint8Array(total) : undefined;
  try {
    for (;;) {
      if (signal.aborted) throw new LoadCancelled();
      const r = await reader.read();
      if (r.done) break;
      if (out && done + r.value.byteLength <= out.byteLength) out.set(r.value, done);
      else {
        if (out) {
          chunks.push(out.subarray(0, done));
          out = undefined;
        }
        chunks.push(r.value);
      }
      done += r.value.byteLength;
      onProgress(done, total);
    }
  } finally {
    reader.releaseLock();
  }
  if (out) return done === out.byteLength ? out : out.slice(0, done);
  const all = new Uint8Array(done);
  let at = 0;
  for (const c of chunks) {
    all.set(c, at);
    at += c.byteLength;
  }
  return all;
}

export function readFile(file: File, onProgress: ReadProgress, signal: AbortSignal): Promise<Uint8Array> {
  return drain(file.stream(), file.size, onProgress, signal);
}

/** Only URLs of this page's origin: the page reads data it serves (or its server proxies). */
export function resolveSameOrigin(url: string): URL {
  const u = new URL(url, location.href);
  if (u.origin !== location.origin) {
    throw new Error(`${url}: only volumes served by this page's own origin (${location.origin}) can be opened with ?url=`);
  }
  return u;
}

export async function fetchVolume(url: URL, onProgress: ReadProgress, signal: AbortSignal): Promise<Uint8Array> {
  let response: Response;
  try {
    response = await fetch(url, { signal });
  } catch (e) {
    if (signal.aborted) throw new LoadCancelled();
    throw new Error(`${url.pathname}: could not be fetched (${(e as Error).message})`);
  }
  if (!response.ok) throw new Error(`${url.pathname}: the server answered ${response.status} ${response.statusText}`.trim());
  const length = Number(response.headers.get('content-length'));
  const encoded = response.headers.get('content-encoding');
  const total = Number.isFinite(length) && length > 0 && !encoded ? length : undefined;
  if (!response.body) return new Uint8Array(await response.arrayBuffer());
  return drain(response.body, total, onProgress, signal);
}

export function fileNameOfUrl(url: URL): string {
  const last =
    url.pathname
      .split('/')
      .filter((s) => s !== '')
      .pop() ?? 'volume';
  return decodeURIComponent(last);
}
