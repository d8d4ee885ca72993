// A Zarr store over HTTP(S) (zarrita's store interface), written so that a
// failed request says what was observed: the HTTP status (and Retry-After),
// a connection that dropped before the answer or in the middle of the body
// (bytes received against Content-Length or the range asked), an attempt
// that timed out, a server that ignored the Range header. Each failure
// carries whether trying again can help (transient) or not (permanent);
// retrying-store.ts does the trying again. 404 is a missing key, as Zarr
// defines it (undefined), not an error.
import type { AbsolutePath, AsyncReadable, GetOptions, RangeQuery } from '@zarrita/storage';
import { TransportError } from './errors.ts';

export interface HttpStoreOptions {
  /** One attempt may take at most this long, answer and body (default 20 s). */
  attemptTimeoutMs?: number;
  /** Injected in tests. */
  fetch?: typeof fetch;
}

/** Bodies larger than this are refused before anything is allocated (a chunk or shard index is far smaller). */
const MAX_BODY_BYTES = 2 ** 30;

function resolveKey(base: string, key: AbsolutePath): string {
  const url = new URL(base);
  if (!url.pathname.endsWith('/')) url.pathname += '/';
  const resolved = new URL(key.slice(1), url);
  resolved.search = url.search;
  return resolved.href;
}

function statusText(r: Response): string {
  return `HTTP ${r.status}${r.statusText ? ` ${r.statusText}` : ''}`;
}

/** Retry-After in milliseconds (delta-seconds or an HTTP date), or undefined. */
export function parseRetryAfter(value: string | null, now = Date.now()): number | undefined {
  if (!value) return undefined;
  const s = value.trim();
  if (/^\d+$/.test(s)) return Number(s) * 1000;
  const t = Date.parse(s);
  return Number.isFinite(t) ? Math.max(0, t - now) : undefined;
}

/** What a fetch rejection says about the connection, as far as the runtime tells. */
function describeFetchFailure(e: unknown): TransportError {
  const err = e as Error & { cause?: { code?: string; message?: string } };
  const code = err.cause?.code ?? '';
  const detail = err.cause?.message ?? err.message;
  if (code === 'ECONNREFUSED') return new TransportError('unreachable', `the connection was refused (${detail})`, true, { cause: e });
  if (code === 'ENOTFOUND' || code === 'EAI_AGAIN')
    return new TransportError('unreachable', `the host was not found (${detail})`, true, { cause: e });
  if (code) return new TransportError('dropped', `the connection dropped before the answer (${code}: ${detail})`, true, { cause: e });
  // a request the runtime will not make at all (a blocked port, a malformed URL)
  if (err.cause && /bad port|invalid|not supported|unsupported/i.test(detail))
    return new TransportError('unreachable', `the request cannot be made (${detail})`, false, { cause: e });
  if (err.cause) return new TransportError('dropped', `the connection dropped before the answer (${detail})`, true, { cause: e });
  // A browser hides the cause (an unreachable host, a CORS refusal and a dropped connection look the same).
  return new TransportError('cors-or-unreachable', `CORS or unreachable (the browser hides the cause: ${err.message})`, true, {
    cause: e,
  });
}

export class HttpStore implements AsyncReadable {
  readonly #fetch: typeof fetch;
  readonly #timeoutMs: number;

  constructor(
    readonly url: string,
    options: HttpStoreOptions = {},
  ) {
    this.#fetch = options.fetch ?? ((input, init) => fetch(input, init));
    this.#timeoutMs = options.attemptTimeoutMs ?? 20_000;
  }

  get(key: AbsolutePath, opts?: GetOptions): Promise<Uint8Array | undefined> {
    return this.#request(key, undefined, opts);
  }

  getRange(key: AbsolutePath, range: RangeQuery, opts?: GetOptions): Promise<Uint8Array | undefined> {
    return this.#request(key, range, opts);
  }

  async #request(key: AbsolutePath, range: RangeQuery | undefined, opts?: GetOptions): Promise<Uint8Array | undefined> {
    const outer = opts?.signal;
    if (outer?.aborted) throw outer.reason ?? new DOMException('aborted', 'AbortError');
    const timeout = new AbortController();
    const timer = setTimeout(
      () => timeout.abort(new TransportError('timeout', `timed out after ${(this.#timeoutMs / 1000).toFixed(1)} s`, true)),
      this.#timeoutMs,
    );
    const signal = outer ? AbortSignal.any([outer, timeout.signal]) : timeout.signal;
    const headers: Record<string, string> = {};
    if (range) {
      headers.Range = 'suffixLength' in range ? `bytes=-${range.suffixLength}` : `bytes=${range.offset}-${range.offset + range.length - 1}`;
    }
    const url = resolveKey(this.url, key);
    try {
      let response: Response;
      try {
        response = await this.#fetch(url, { headers, signal, cache: 'no-store' });
      } catch (e) {
        throw this.#failure(e, outer, timeout.signal);
      }
      if (response.status === 404) {
        void response.body?.cancel().catch(() => {});
        return undefined;
      }
      if (response.status !== 200 && response.status !== 206) {
        void response.body?.cancel().catch(() => {});
        throw statusError(response);
      }
      if (range && response.status === 200) {
        void response.body?.cancel().catch(() => {});
        throw new TransportError(
          'range-ignored',
          `the server ignored the Range header (HTTP 200 with the whole file where ${headers.Range} was asked); sharded stores need a server that honours Range requests`,
          false,
        );
      }
      const expected = expectedLength(response, range);
      try {
        return await readBody(response, expected);
      } catch (e) {
        if (e instanceof TransportError) throw e;
        throw this.#failure(e, outer, timeout.signal, 'body');
      }
    } finally {
      clearTimeout(timer);
    }
  }

  #failure(e: unknown, outer: AbortSignal | undefined, timeout: AbortSignal, phase: 'answer' | 'body' = 'answer'): unknown {
    if (outer?.aborted) return outer.reason ?? e;
    if (timeout.aborted) return timeout.reason;
    if ((e as Error)?.name === 'AbortError') return e;
    if (e instanceof TransportError) return e;
    if (phase === 'body') {
      const err = e as Error & { cause?: { message?: string } };
      return new TransportError('dropped', `the connection dropped in the body (${err.cause?.message ?? err.message})`, true, {
        cause: e,
      });
    }
    return describeFetchFailure(e);
  }
}

function statusError(r: Response): TransportError {
  const s = r.status;
  if (s === 429 || s === 503) {
    const after = parseRetryAfter(r.headers.get('Retry-After'));
    const text = `${statusText(r)}${after !== undefined ? ` (Retry-After ${(after / 1000).toFixed(0)} s)` : ''}`;
    return new TransportError('http', text, true, { status: s, retryAfterMs: after });
  }
  // 5xx and 408 (request timeout) are the server's or a proxy's passing trouble; the rest are answers.
  const transient = s >= 500 || s === 408;
  return new TransportError('http', statusText(r), transient, { status: s });
}

/** Bytes the body must have: the range asked (206), else Content-Length when the body is not re-encoded; undefined if unknown. */
function expectedLength(r: Response, range: RangeQuery | undefined): number | undefined {
  const encoding = r.headers.get('Content-Encoding');
  const length = r.headers.get('Content-Length');
  let n: number | undefined;
  if ((!encoding || encoding === 'identity') && length !== null && /^\d+$/.test(length.trim())) n = Number(length);
  if (range && r.status === 206 && !('suffixLength' in range)) {
    if (n !== undefined && n !== range.length)
      throw new TransportError('corrupt', `the server answered ${n} bytes where the range asked ${range.length}`, false);
    n = range.length;
  }
  if (n !== undefined && n > MAX_BODY_BYTES)
    throw new TransportError(
      'corrupt',
      `the answer announces ${n} bytes, more than ${MAX_BODY_BYTES} this reader takes per request`,
      false,
    );
  return n;
}

/** The body, counting bytes as they come, so a cut connection says how much arrived. */
async function readBody(r: Response, expected: number | undefined): Promise<Uint8Array> {
  if (!r.body) return new Uint8Array(0);
  const reader = r.body.getReader();
  const parts: Uint8Array[] = [];
  let received = 0;
  try {
    for (;;) {
      const { done, value } = await reader.read();
      if (done) break;
      received += value.byteLength;
      if (received > MAX_BODY_BYTES)
        throw new TransportError('corrupt', `the answer is longer than ${MAX_BODY_BYTES} bytes this reader takes per request`, false);
      parts.push(value);
    }
  } catch (e) {
    if (e instanceof TransportError || (e as Error)?.name === 'AbortError') throw e;
    const of = expected !== undefined ? ` of ${expected}` : '';
    throw new TransportError('truncated', `the connection dropped after ${received}${of} bytes of the body`, true, { cause: e });
  }
  if (expected !== undefined && received !== expected) {
    throw new TransportError(
      'truncated',
      received < expected
        ? `the body ended after ${received} of ${expected} bytes (Content-Length)`
        : `the body has ${received} bytes, Content-Length said ${expected}`,
      true,
    );
  }
  if (parts.length === 1) return parts[0];
  const out = new Uint8Array(received);
  let at = 0;
  for (const p of parts) {
    out.set(p, at);
    at += p.byteLength;
  }
  return out;
}
