/** Why a store, level or chunk was refused; the message names the store (and level / chunk). */
export type StoreErrorKind =
  | 'unreachable'
  | 'cors'
  | 'not-found'
  | 'http'
  | 'network'
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

/** What one attempt of a request observed (http-store.ts). */
export type TransportKind =
  | 'http'
  | 'dropped'
  | 'truncated'
  | 'timeout'
  | 'unreachable'
  | 'cors-or-unreachable'
  | 'range-ignored'
  | 'corrupt';

/**
 * One failed attempt of a request, in the words of what was seen (status,
 * bytes received, time waited); `transient` says whether trying again can help.
 */
export class TransportError extends Error {
  readonly status?: number;
  readonly retryAfterMs?: number;
  constructor(
    readonly transportKind: TransportKind,
    message: string,
    readonly transient: boolean,
    extra: { status?: number; retryAfterMs?: number; cause?: unknown } = {},
  ) {
    super(message, extra.cause === undefined ? undefined : { cause: extra.cause });
    this.name = 'TransportError';
    this.status = extra.status;
    this.retryAfterMs = extra.retryAfterMs;
  }
}

/**
 * A request that failed for good (retrying-store.ts): its message is what was
 * observed and how long it was tried ("GET /0/c/0/0/1: HTTP 503 Service
 * Unavailable, 9 tries over 30.4 s"); describeTransportError puts what it was
 * for (store, level, chunk) in front.
 */
export class RequestFailedError extends StoreError {
  constructor(
    kind: StoreErrorKind,
    message: string,
    readonly last: TransportError,
  ) {
    super(kind, message, { cause: last });
    this.name = 'RequestFailedError';
  }
}

export function isAbort(e: unknown): boolean {
  return (e as { name?: string })?.name === 'AbortError';
}

/** The StoreError kind of a request's last failure. */
export function storeErrorKind(e: TransportError): StoreErrorKind {
  switch (e.transportKind) {
    case 'http':
      return e.status === 403 || e.status === 401 ? 'unreachable' : 'http';
    case 'cors-or-unreachable':
      return 'cors';
    case 'unreachable':
      return 'unreachable';
    case 'corrupt':
    case 'range-ignored':
      return 'corrupt';
    default:
      return 'network';
  }
}

/**
 * A failure of the store's transport, in words, for `what` (the store, a
 * level, a chunk): a request that failed for good (its observation), an abort,
 * or whatever a store other than ours threw (zarrita's FetchStore says
 * "Unexpected response status N"; a folder store, ENOENT and the like).
 */
export function describeTransportError(e: unknown, what: string): StoreError {
  if (e instanceof RequestFailedError) {
    const hint =
      e.kind === 'cors'
        ? ': a store on another origin must send Access-Control-Allow-Origin and allow the Range header, and the host must be reachable'
        : '';
    return new StoreError(e.kind, `${what}: ${e.message}${hint}`, { cause: e });
  }
  if (e instanceof StoreError) return e;
  if (isAbort(e)) return new StoreError('aborted', `${what}: aborted`, { cause: e });
  if (e instanceof TransportError) return new StoreError(storeErrorKind(e), `${what}: ${e.message}`, { cause: e });
  const message = e instanceof Error ? e.message : String(e);
  if (e instanceof TypeError && /fetch|network|load failed/i.test(message)) {
    return new StoreError(
      'cors',
      `${what}: the request failed (${message}): CORS or unreachable. A store on another origin must send Access-Control-Allow-Origin and allow the Range header`,
      { cause: e },
    );
  }
  const status = /status (\d+)/.exec(message);
  if (status) return new StoreError('http', `${what}: the server answered HTTP ${status[1]}`, { cause: e });
  return new StoreError('unreachable', `${what}: ${message}`, { cause: e });
}
