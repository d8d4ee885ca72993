// Catches allocations above a limit while a fuzz case runs: the global
// ArrayBuffer and typed-array constructors are wrapped (module code looks them
// up on the global object at each call), and a request above the limit throws
// an AllocationLimitError instead of allocating, which the runner counts as an
// absurd allocation. Allocations made inside the engine (Blob/Response
// buffers, slice(), Wasm memory growth) do not pass through the constructors;
// the runner's memory sampling (rss, arrayBuffers) covers those.

export class AllocationLimitError extends Error {
  constructor(
    readonly requestedBytes: number,
    readonly limitBytes: number,
    what: string,
  ) {
    super(`fuzz guard: ${what} of ${requestedBytes} bytes requested (limit ${limitBytes})`);
    this.name = 'AllocationLimitError';
  }
}

const NAMES = [
  'ArrayBuffer',
  'SharedArrayBuffer',
  'Uint8Array',
  'Uint8ClampedArray',
  'Int8Array',
  'Uint16Array',
  'Int16Array',
  'Uint32Array',
  'Int32Array',
  'Float32Array',
  'Float64Array',
  'BigInt64Array',
  'BigUint64Array',
] as const;

type Ctor = new (...args: unknown[]) => unknown;

export interface AllocationGuard {
  /** Largest single request seen since install (bytes). */
  largest: number;
  release(): void;
}

/** Wraps the constructors until `release()`; requests above `limitBytes` throw. */
export function installAllocationGuard(limitBytes: number): AllocationGuard {
  const g = globalThis as unknown as Record<string, Ctor>;
  const originals = new Map<string, Ctor>();
  const guard: AllocationGuard = {
    largest: 0,
    release() {
      for (const [name, ctor] of originals) g[name] = ctor;
      originals.clear();
    },
  };
  for (const name of NAMES) {
    const original = g[name];
    if (!original) continue;
    const width = name.endsWith('Buffer') ? 1 : ((original as unknown as { BYTES_PER_ELEMENT: number }).BYTES_PER_ELEMENT ?? 1);
    originals.set(name, original);
    g[name] = new Proxy(original, {
      construct(target, args, newTarget) {
        const n = args[0];
        if (typeof n === 'number' && Number.isFinite(n) && n >= 0) {
          const bytes = n * width;
          if (bytes > guard.largest) guard.largest = bytes;
          if (bytes > limitBytes) throw new AllocationLimitError(bytes, limitBytes, `new ${name}(${n})`);
        }
        return Reflect.construct(target, args, newTarget === g[name] ? target : newTarget);
      },
    });
  }
  return guard;
}
