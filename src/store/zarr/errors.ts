/** Why a store, level or chunk was refused; the message names the store (and level / chunk). */
export type StoreErrorKind =
  | 'unreachable'
  | 'cors'
  | 'not-found'
  | 'http'
  | 'not-a-store'
  | 'codec'
  | 'layout'
  | 'corrupt'
  | 'missing-chunk'
  | 'aborted';

export class StoreError extends Error {
  constructor(
    readonly kind: StoreErrorKind,
    message: string,
    options?: { cause?: unknown },
  ) {
    super(message, options);
    this.name = 'StoreError';
  }
}

export function isAbort(e: unknown): boolean {
  return (e as { name?: string })?.name === 'AbortError';
}

/**
 * A failure of the store's transport, in words: fetch rejects with a TypeError
 * for an unreachable host and for a CORS refusal alike (the page cannot tell
 * them apart), zarrita's FetchStore throws "Unexpected response status N".
 */
export function describeTransportError(e: unknown, what: string): StoreError {
  if (e instanceof StoreError) return e;
  if (isAbort(e)) return new StoreError('aborted', `${what}: aborted`, { cause: e });
  const message = e instanceof Error ? e.message : String(e);
  if (e instanceof TypeError && /fetch|network|load failed/i.test(message)) {
    return new StoreError(
      'cors',
      `${what}: the request failed (${message}). The host is unreachable, or it refused this page (CORS): a store on another origin must send Access-Control-Allow-Origin and allow the Range header`,
      { cause: e },
    );
  }
  const status = /status (\d+)/.exec(message);
  if (status) return new StoreError('http', `${what}: the server answered HTTP ${status[1]}`, { cause: e });
  if (/ENOENT|ENOTDIR|EACCES/.test(message)) return new StoreError('unreachable', `${what}: ${message}`, { cause: e });
  return new StoreError('unreachable', `${what}: ${message}`, { cause: e });
}
