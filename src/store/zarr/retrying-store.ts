// Every request of a store tried again while trying again can help: the
// metadata, the range arrays, shard indexes and chunks alike (everything
// zarrita and our reader ask of the store goes through here). Transient
// failures (5xx, 408, 429 and 503 with their Retry-After, dropped and cut
// connections, timeouts) are retried with exponential backoff and jitter
// until a per-request deadline; permanent ones (403, a Range ignored, a
// malformed answer) fail at once. A count of tries would not do: at 30%
// independent faults, 3 tries leave 1 request in 37 failing, and an open is a
// few hundred requests. A host that has never answered and cannot be
// reached (in the page: CORS or unreachable, which the browser does not tell
// apart) gets only a few quick tries: it is most likely a wrong URL or a
// CORS refusal, which no waiting fixes.
import type { AbsolutePath, AsyncReadable, GetOptions, RangeQuery } from '@zarrita/storage';
import { RequestFailedError, storeErrorKind, TransportError } from './errors.ts';

export interface RetryPolicy {
  /** A request gives up once this much time has passed since its first try (default 30 s). */
  deadlineMs?: number;
  /** First backoff; doubles per try up to maxDelayMs (defaults 200 ms, 5 s). */
  firstDelayMs?: number;
  maxDelayMs?: number;
  /** Tries for a host that has never answered and cannot be reached (default 3). */
  unreachableTries?: number;
  /** Injected in tests. */
  random?: () => number;
  sleep?: (ms: number, signal?: AbortSignal) => Promise<void>;
  now?: () => number;
}

export interface RetryCounters {
  /** Tries after a failed one. */
  retries: number;
  /** Requests that failed for good. */
  failed: number;
  /** Failed tries by what was observed ("HTTP 503", "dropped", "truncated", "timeout", ...). */
  faults: Record<string, number>;
}

export function sleepFor(ms: number, signal?: AbortSignal): Promise<void> {
  return new Promise((resolve, reject) => {
    if (signal?.aborted) {
      reject(signal.reason ?? new DOMException('aborted', 'AbortError'));
      return;
    }
    const onAbort = () => {
      clearTimeout(timer);
      reject(signal!.reason ?? new DOMException('aborted', 'AbortError'));
    };
    const timer = setTimeout(() => {
      signal?.removeEventListener('abort', onAbort);
      resolve();
    }, ms);
    signal?.addEventListener('abort', onAbort, { once: true });
  });
}

function describeRange(range: RangeQuery | undefined): string {
  if (!range) return '';
  return 'suffixLength' in range ? ` (last ${range.suffixLength} bytes)` : ` (bytes ${range.offset}-${range.offset + range.length - 1})`;
}

export class RetryingStore implements AsyncReadable {
  readonly counters: RetryCounters = { retries: 0, failed: 0, faults: {} };
  readonly #deadlineMs: number;
  readonly #firstDelayMs: number;
  readonly #maxDelayMs: number;
  readonly #unreachableTries: number;
  readonly #random: () => number;
  readonly #sleep: (ms: number, signal?: AbortSignal) => Promise<void>;
  readonly #now: () => number;
  /** Whether the host has answered at least once (then a lost connection is a dropped one, not a wrong URL). */
  #answered = false;

  constructor(
    readonly inner: AsyncReadable,
    policy: RetryPolicy = {},
  ) {
    this.#deadlineMs = policy.deadlineMs ?? 30_000;
    this.#firstDelayMs = policy.firstDelayMs ?? 200;
    this.#maxDelayMs = policy.maxDelayMs ?? 5_000;
    this.#unreachableTries = policy.unreachableTries ?? 3;
    this.#random = policy.random ?? Math.random;
    this.#sleep = policy.sleep ?? sleepFor;
    this.#now = policy.now ?? (() => performance.now());
  }

  get(key: AbsolutePath, opts?: GetOptions): Promise<Uint8Array | undefined> {
    return this.#try(`GET ${key}`, () => this.inner.get(key, opts), opts?.signal);
  }

  getRange(key: AbsolutePath, range: RangeQuery, opts?: GetOptions): Promise<Uint8Array | undefined> {
    const inner = this.inner;
    if (!inner.getRange) return this.get(key, opts);
    return this.#try(`GET ${key}${describeRange(range)}`, () => inner.getRange!(key, range, opts), opts?.signal);
  }

  async #try(what: string, attempt: () => Promise<Uint8Array | undefined>, signal?: AbortSignal): Promise<Uint8Array | undefined> {
    const start = this.#now();
    for (let tries = 1; ; tries++) {
      try {
        const bytes = await attempt();
        this.#answered = true;
        return bytes;
      } catch (e) {
        if (!(e instanceof TransportError)) throw e; // aborts, and what other stores throw: not ours to retry
        const label = e.transportKind === 'http' ? `HTTP ${e.status}` : e.transportKind;
        this.counters.faults[label] = (this.counters.faults[label] ?? 0) + 1;
        if (e.transportKind === 'http' || e.transportKind === 'truncated' || e.transportKind === 'range-ignored') this.#answered = true;
        const elapsed = this.#now() - start;
        const fail = (why = '') => {
          this.counters.failed++;
          const over = tries > 1 ? `, ${tries} tries over ${(elapsed / 1000).toFixed(1)} s` : '';
          return new RequestFailedError(storeErrorKind(e), `${what}: ${e.message}${over}${why}`, e);
        };
        const unreachable = e.transportKind === 'unreachable' || e.transportKind === 'cors-or-unreachable';
        if (!e.transient) throw fail();
        if (unreachable && !this.#answered && tries >= this.#unreachableTries) throw fail();
        const backoff = Math.min(this.#maxDelayMs, this.#firstDelayMs * 2 ** (tries - 1));
        // equal jitter: half the backoff, plus up to the other half at random (requests that failed together spread out)
        let delay = backoff / 2 + (this.#random() * backoff) / 2;
        if (e.retryAfterMs !== undefined) delay = Math.max(delay, e.retryAfterMs);
        if (elapsed + delay >= this.#deadlineMs) {
          throw fail(
            e.retryAfterMs !== undefined && e.retryAfterMs > this.#deadlineMs - elapsed
              ? ` (the server asks to wait ${(e.retryAfterMs / 1000).toFixed(0)} s, past the ${(this.#deadlineMs / 1000).toFixed(0)} s deadline)`
              : '',
          );
        }
        this.counters.retries++;
        await this.#sleep(delay, signal);
      }
    }
  }
}
