// The part of vitest's API our GPU unit tests use (describe, test, hooks,
// expect), for running them outside vitest: in Deno on wgpu (run.ts).
// Tests register here and run one after another.

type Fn = () => unknown | Promise<unknown>;
export interface Registered {
  name: string;
  fn: Fn;
  timeoutMs: number;
  /** beforeAll/afterAll hooks of the file the test is in. */
  file: FileHooks;
}
interface FileHooks {
  beforeAll: Fn[];
  afterAll: Fn[];
}

export const registered: Registered[] = [];
const prefix: string[] = [];
let hooks: FileHooks = { beforeAll: [], afterAll: [] };

/** Starts a new test file: hooks registered from here on belong to it. */
export function beginFile(): void {
  hooks = { beforeAll: [], afterAll: [] };
}

export function describe(name: string, body: () => void): void {
  prefix.push(name);
  try {
    body();
  } finally {
    prefix.pop();
  }
}

export function test(name: string, fn: Fn, timeoutMs = 120_000): void {
  registered.push({ name: [...prefix, name].join(' > '), fn, timeoutMs, file: hooks });
}
/** vitest's name formatting for `.for`/`.each`: %i %d %f %s %j %o take the case's values in order. */
export function formatName(name: string, c: unknown): string {
  const values = Array.isArray(c) ? [...c] : [c];
  return name.replace(/%[idfsjo%]/g, (m) => (m === '%%' ? '%' : show(values.shift())));
}

/** `test.for(cases)(name, (case, ctx) => ...)` */
test.for =
  <T>(cases: readonly T[]) =>
  (name: string, fn: (c: T, ctx: object) => unknown, timeoutMs?: number) => {
    for (const c of cases) test(formatName(name, c), () => fn(c, {}), timeoutMs);
  };
export const it = test;

export function beforeAll(fn: Fn): void {
  hooks.beforeAll.push(fn);
}
export function afterAll(fn: Fn): void {
  hooks.afterAll.push(fn);
}

// ---- expect ----

function show(v: unknown): string {
  if (typeof v === 'bigint') return `${v}n`;
  if (ArrayBuffer.isView(v)) {
    const a = Array.from(v as unknown as ArrayLike<number>);
    return `${v.constructor.name}(${a.length}) [${a.slice(0, 8).join(', ')}${a.length > 8 ? ', ...' : ''}]`;
  }
  try {
    const s = JSON.stringify(v, (_k, x) => (typeof x === 'bigint' ? `${x}n` : x));
    return s === undefined ? String(v) : s.length > 300 ? `${s.slice(0, 300)}...` : s;
  } catch {
    return String(v);
  }
}

function firstDifference(a: unknown, b: unknown, path = ''): string | undefined {
  if (Object.is(a, b)) return undefined;
  if (typeof a !== 'object' || typeof b !== 'object' || a === null || b === null) return `${path || 'value'}: ${show(a)} vs ${show(b)}`;
  if (ArrayBuffer.isView(a) || ArrayBuffer.isView(b)) {
    if (!ArrayBuffer.isView(a) || !ArrayBuffer.isView(b) || a.constructor !== b.constructor)
      return `${path || 'value'}: ${show(a)} vs ${show(b)}`;
    const x = a as unknown as ArrayLike<number>;
    const y = b as unknown as ArrayLike<number>;
    if (x.length !== y.length) return `${path || 'value'}: length ${x.length} vs ${y.length}`;
    for (let i = 0; i < x.length; i++) if (!Object.is(x[i], y[i])) return `${path}[${i}]: ${x[i]} vs ${y[i]}`;
    return undefined;
  }
  if (Array.isArray(a) !== Array.isArray(b)) return `${path || 'value'}: ${show(a)} vs ${show(b)}`;
  if (a instanceof Map || a instanceof Set)
    return firstDifference([...(a as Map<unknown, unknown>)], [...(b as Map<unknown, unknown>)], path);
  const ka = Object.keys(a).filter((k) => (a as Record<string, unknown>)[k] !== undefined);
  const kb = Object.keys(b).filter((k) => (b as Record<string, unknown>)[k] !== undefined);
  for (const k of new Set([...ka, ...kb])) {
    const d = firstDifference((a as Record<string, unknown>)[k], (b as Record<string, unknown>)[k], `${path}.${k}`);
    if (d) return d;
  }
  return undefined;
}

function matchesObject(actual: unknown, expected: unknown): boolean {
  if (typeof expected !== 'object' || expected === null) return Object.is(actual, expected);
  if (typeof actual !== 'object' || actual === null) return false;
  if (Array.isArray(expected)) return firstDifference(actual, expected) === undefined;
  return Object.entries(expected).every(([k, v]) => matchesObject((actual as Record<string, unknown>)[k], v));
}

function thrownBy(fn: unknown): { threw: boolean; error?: unknown } {
  try {
    (fn as () => unknown)();
    return { threw: false };
  } catch (error) {
    return { threw: true, error };
  }
}

function errorMatches(error: unknown, want: unknown): boolean {
  if (want === undefined) return true;
  const message = error instanceof Error ? error.message : String(error);
  if (typeof want === 'string') return message.includes(want);
  if (want instanceof RegExp) return want.test(message);
  if (typeof want === 'function') return error instanceof (want as new () => unknown);
  return matchesObject(error, want);
}

function matchers(actual: unknown, negate: boolean) {
  const check = (ok: boolean, what: string) => {
    if (ok === negate) throw new Error(`expected ${show(actual)} ${negate ? 'not ' : ''}${what}`);
  };
  const num = (x: unknown) => x as number;
  return {
    toBe: (e: unknown) => check(Object.is(actual, e), `to be ${show(e)}`),
    toEqual: (e: unknown) => {
      const d = firstDifference(actual, e);
      if ((d === undefined) === negate)
        throw new Error(negate ? `expected ${show(actual)} not to equal it` : `expected equal values; first difference ${d}`);
    },
    toStrictEqual: (e: unknown) => check(firstDifference(actual, e) === undefined, `to equal ${show(e)}`),
    toBeGreaterThan: (e: number | bigint) => check(num(actual) > num(e), `to be > ${e}`),
    toBeGreaterThanOrEqual: (e: number | bigint) => check(num(actual) >= num(e), `to be >= ${e}`),
    toBeLessThan: (e: number | bigint) => check(num(actual) < num(e), `to be < ${e}`),
    toBeLessThanOrEqual: (e: number | bigint) => check(num(actual) <= num(e), `to be <= ${e}`),
    toBeCloseTo: (e: number, digits = 2) => check(Math.abs(num(actual) - e) < 10 ** -digits / 2, `to be close to ${e}`),
    toBeInstanceOf: (c: new (...a: never[]) => unknown) => check(actual instanceof c, `to be an instance of ${c.name}`),
    toBeDefined: () => check(actual !== undefined, 'to be defined'),
    toBeUndefined: () => check(actual === undefined, 'to be undefined'),
    toBeNull: () => check(actual === null, 'to be null'),
    toBeTruthy: () => check(!!actual, 'to be truthy'),
    toBeFalsy: () => check(!actual, 'to be falsy'),
    toBeNaN: () => check(Number.isNaN(actual), 'to be NaN'),
    toContain: (e: unknown) => check((actual as { includes(x: unknown): boolean }).includes(e), `to contain ${show(e)}`),
    toHaveLength: (n: number) => check((actual as { length: number }).length === n, `to have length ${n}`),
    toMatch: (e: string | RegExp) => check(typeof e === 'string' ? String(actual).includes(e) : e.test(String(actual)), `to match ${e}`),
    toMatchObject: (e: unknown) => check(matchesObject(actual, e), `to match ${show(e)}`),
    toThrow: (want?: unknown) => {
      const r = thrownBy(actual);
      const ok = r.threw && errorMatches(r.error, want);
      if (ok === negate)
        throw new Error(
          `expected the function ${negate ? 'not ' : ''}to throw${want === undefined ? '' : ` ${show(String(want))}`}${r.threw ? `; it threw: ${(r.error as Error)?.message ?? r.error}` : '; it did not throw'}`,
        );
    },
  };
}
type Matchers = ReturnType<typeof matchers>;
type AsyncMatchers = { [K in keyof Matchers]: (...a: Parameters<Matchers[K]>) => Promise<void> };

export function expect(actual: unknown) {
  const settled = async (wantReject: boolean) => {
    try {
      const value = await actual;
      if (wantReject) throw Object.assign(new Error(`expected a rejection, got ${show(value)}`), { noRejection: true });
      return value;
    } catch (e) {
      if ((e as { noRejection?: boolean }).noRejection) throw e;
      if (!wantReject) throw e;
      return e;
    }
  };
  const asyncMatchers = (wantReject: boolean, negate: boolean): AsyncMatchers => {
    const out: Record<string, unknown> = {};
    for (const name of Object.keys(matchers(undefined, false))) {
      out[name] = async (...args: unknown[]) => {
        const v = await settled(wantReject);
        // `rejects.toThrow(x)` checks the rejection's error like vitest does.
        const m = matchers(
          name === 'toThrow' && wantReject
            ? () => {
                throw v;
              }
            : v,
          negate,
        ) as unknown as Record<string, (...a: unknown[]) => void>;
        m[name](...args);
      };
    }
    return out as AsyncMatchers;
  };
  return Object.assign(matchers(actual, false), {
    not: matchers(actual, true),
    rejects: Object.assign(asyncMatchers(true, false), { not: asyncMatchers(true, true) }),
    resolves: Object.assign(asyncMatchers(false, false), { not: asyncMatchers(false, true) }),
  });
}
