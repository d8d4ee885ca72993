// A misbehaving object store, for the tests and `bench:stream --faults`: the
// /stores/ middleware (vite-stores.ts) serves
//   /stores/~faults(rate=0.3;seed=7[;kinds=500,503,429,drop,truncate,slow,403][;match=TEXT])/NAME.zarr/...
// as NAME.zarr, failing each attempt with probability `rate` the ways object
// stores and proxies fail: HTTP 500, 503 and 429 (both with Retry-After: 1),
// a connection dropped before the answer, a body cut after its headers
// (Content-Length promises more), or an answer held back (slow, then
// correct); those are the default kinds. 403 (a permanent refusal) only
// when asked for. Every kind of request is hit (metadata, range arrays, shard
// indexes, chunks). `match` limits the faults to paths containing TEXT (one
// chunk at 100%). Decisions are a hash of the seed, the request (path and
// range) and how many times that request came before, so they are seeded and
// independent per attempt whatever order concurrent requests arrive in.
import type { IncomingMessage, ServerResponse } from 'node:http';

export type FaultKind = '500' | '503' | '429' | 'drop' | 'truncate' | 'slow' | '403';
/** The kinds a server passing through trouble shows (the default). */
export const TRANSIENT_FAULTS: readonly FaultKind[] = ['500', '503', '429', 'drop', 'truncate', 'slow'];
const ALL_KINDS: readonly FaultKind[] = [...TRANSIENT_FAULTS, '403'];

export interface FaultSpec {
  rate: number;
  seed: number;
  kinds: FaultKind[];
  match: string | null;
}

/** The spec in a /stores/~faults(...)/ prefix, and the path after it; null when the URL has none. */
export function parseFaultPrefix(path: string): { spec: FaultSpec; rest: string } | null {
  const m = /^~faults\(([^)]*)\)\/(.*)$/.exec(path);
  if (!m) return null;
  const spec: FaultSpec = { rate: 0, seed: 1, kinds: [...TRANSIENT_FAULTS], match: null };
  for (const part of m[1].split(';')) {
    const [k, v = ''] = part.split('=');
    if (k === 'rate') spec.rate = Math.min(1, Math.max(0, Number(v) || 0));
    else if (k === 'seed') spec.seed = Math.trunc(Number(v) || 0);
    else if (k === 'kinds') spec.kinds = v.split(',').filter((x): x is FaultKind => (ALL_KINDS as readonly string[]).includes(x));
    else if (k === 'match') spec.match = decodeURIComponent(v);
  }
  if (spec.kinds.length === 0) spec.kinds = [...TRANSIENT_FAULTS];
  return { spec, rest: m[2] };
}

/** The URL prefix for a spec (tests and benchmarks build store URLs with it). */
export function faultPrefix(spec: Partial<FaultSpec> & { rate: number }): string {
  const parts = [`rate=${spec.rate}`, `seed=${spec.seed ?? 1}`];
  if (spec.kinds) parts.push(`kinds=${spec.kinds.join(',')}`);
  if (spec.match) parts.push(`match=${encodeURIComponent(spec.match)}`);
  return `~faults(${parts.join(';')})`;
}

/** FNV-1a of the text, then a final mix: a number in [0, 1). */
function unit(text: string): number {
  let h = 0x811c9dc5;
  for (let i = 0; i < text.length; i++) h = Math.imul(h ^ text.charCodeAt(i), 0x01000193);
  h ^= h >>> 16;
  h = Math.imul(h, 0x85ebca6b);
  h ^= h >>> 13;
  h = Math.imul(h, 0xc2b2ae35);
  h ^= h >>> 16;
  return (h >>> 0) / 2 ** 32;
}

/** Counts attempts per request and decides each one's fault. One per server (attempt counts are its memory). */
export class FaultInjector {
  readonly #attempts = new Map<string, number>();
  /** Faults injected, by kind (for the tests and the benchmark's table). */
  readonly injected: Record<string, number> = {};
  /** Faults injected, by what was asked: metadata (zarr.json), range arrays, shard indexes (suffix ranges), chunks. */
  readonly injectedOn: Record<'metadata' | 'ranges' | 'shard index' | 'chunk', number> = {
    metadata: 0,
    ranges: 0,
    'shard index': 0,
    chunk: 0,
  };

  decide(spec: FaultSpec, method: string, path: string, range: string | undefined): FaultKind | null {
    if (spec.rate <= 0 || (spec.match && !path.includes(spec.match))) return null;
    const request = `${method} ${path} ${range ?? ''}`;
    const attempt = (this.#attempts.get(request) ?? 0) + 1;
    this.#attempts.set(request, attempt);
    const key = `${spec.seed}|${request}|${attempt}`;
    if (unit(key) >= spec.rate) return null;
    const kind = spec.kinds[Math.floor(unit(`${key}|kind`) * spec.kinds.length)];
    this.injected[kind] = (this.injected[kind] ?? 0) + 1;
    const what = path.endsWith('zarr.json')
      ? 'metadata'
      : /(^|\/)ranges\//.test(path)
        ? 'ranges'
        : range?.startsWith('bytes=-')
          ? 'shard index'
          : 'chunk';
    this.injectedOn[what]++;
    return kind;
  }

  /**
   * Answers with the fault, or (slow) delays and returns 'continue'. `serve`
   * writes the real answer; a truncated one is cut in the middle of its body.
   */
  apply(kind: FaultKind, req: IncomingMessage, res: ServerResponse, serve: (cut?: number) => void): void {
    switch (kind) {
      case '500':
        res.statusCode = 500;
        res.end('injected fault');
        return;
      case '403':
        res.statusCode = 403;
        res.end('Forbidden');
        return;
      case '503':
      case '429':
        res.statusCode = Number(kind);
        res.setHeader('Retry-After', '1');
        res.end(kind === '503' ? 'Slow Down' : 'Too Many Requests');
        return;
      case 'drop':
        req.socket.destroy();
        return;
      case 'truncate':
        serve(0.5);
        return;
      case 'slow':
        setTimeout(() => serve(), 200 + Math.floor(unit(`${req.url}|slow`) * 800));
        return;
    }
  }
}
