// Shared pieces of the primitives tests: a seeded PRNG, buffers filled from
// the host, poisoned outputs, GPU-side counts, and typed-array comparison
// that reports the first mismatches instead of one expect per element.
import { readU32 } from '../../../src/gpu/buffers.ts';
import type { GpuCount } from '../../../src/gpu/buffer-ref.ts';

export const POISON = 0xdeadbeef;

/** Both kernel families (src/primitives/README.md), each forced by the `path` option. */
export const PATHS = ['emulator', 'gpu'] as const;

/**
 * The variants of a primitive with a workgroup scan: both paths, the GPU path
 * without and with subgroups (the latter only where the device has them).
 */
export const SCAN_VARIANTS = [
  { name: 'emulator', path: 'emulator', subgroups: false },
  { name: 'gpu', path: 'gpu', subgroups: false },
  { name: 'gpu+subgroups', path: 'gpu', subgroups: true },
] as const;
export type ScanVariant = (typeof SCAN_VARIANTS)[number];

/** The options forcing a variant, or undefined where the device lacks its feature (the test then has nothing to run). */
export function variantOptions(device: GPUDevice, v: ScanVariant): { path: ScanVariant['path']; subgroups: boolean } | undefined {
  if (v.subgroups && !device.features.has('subgroups' as GPUFeatureName)) {
    console.warn(`${v.name}: the device has no 'subgroups' feature; variant not run`);
    return undefined;
  }
  return { path: v.path, subgroups: v.subgroups };
}

/**
 * Large sizes per path: the GPU path's workgroup-memory kernels are slow on
 * SwiftShader, so it gets the grid-limit size and 2^20 + 3 (its tile is 1024).
 */
export function largeSizes(path: (typeof PATHS)[number]): number[] {
  return path === 'gpu' ? [65535 * 64 + 1, 2 ** 20 + 3] : LARGE_SIZES;
}

/** The sizes the issue asks for, small to large. */
export const SMALL_SIZES = [0, 1, 2, 63, 64, 65, 255, 256, 257, 4095, 65535, 65536];
export const LARGE_SIZES = [65535 * 256 + 1, 2 ** 20 + 3, 2 ** 24];

/** xorshift32: deterministic inputs per seed. */
export function rng(seed: number): () => number {
  let s = seed >>> 0 || 0x9e3779b9;
  return () => {
    s ^= s << 13;
    s >>>= 0;
    s ^= s >>> 17;
    s ^= s << 5;
    s >>>= 0;
    return s;
  };
}

export function randomU32(n: number, seed: number): Uint32Array<ArrayBuffer> {
  const next = rng(seed);
  const a = new Uint32Array(n);
  for (let i = 0; i < n; i++) a[i] = next();
  return a;
}

/** 0/1 mask with the given density of ones (0..1). */
export function randomMask(n: number, density: number, seed: number): Uint32Array<ArrayBuffer> {
  const next = rng(seed);
  const a = new Uint32Array(n);
  if (density >= 1) return a.fill(1);
  const threshold = Math.floor(density * 2 ** 32);
  for (let i = 0; i < n; i++) a[i] = next() < threshold ? 1 : 0;
  return a;
}

export function storageIo(): GPUBufferUsageFlags {
  return GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST;
}

/** A storage buffer of `length` u32 holding `data` followed by POISON. */
export function upload(device: GPUDevice, label: string, data: Uint32Array, length = data.length, usage = storageIo()): GPUBuffer {
  const buffer = device.createBuffer({ label, size: Math.max(4, length * 4), usage, mappedAtCreation: true });
  const view = new Uint32Array(buffer.getMappedRange());
  view.fill(POISON);
  view.set(data.subarray(0, Math.min(data.length, length)));
  buffer.unmap();
  return buffer;
}

/** Overwrites a whole buffer with POISON (queue-ordered, before the next submit). */
export function poison(device: GPUDevice, buffer: GPUBuffer): void {
  device.queue.writeBuffer(buffer, 0, new Uint32Array(buffer.size / 4).fill(POISON));
}

/**
 * A count in a GPU buffer at a non-zero offset, as an earlier kernel would
 * leave it: the buffer also holds other words.
 */
export function gpuCount(device: GPUDevice, value: number, offset = 8): GpuCount {
  const words = new Uint32Array(offset / 4 + 2).fill(POISON);
  words[offset / 4] = value;
  const buffer = device.createBuffer({ label: 'test.count', size: words.byteLength, usage: storageIo(), mappedAtCreation: true });
  new Uint32Array(buffer.getMappedRange()).set(words);
  buffer.unmap();
  return { buffer, offset };
}

export async function read(device: GPUDevice, buffer: GPUBuffer, count?: number): Promise<Uint32Array> {
  return readU32(device, buffer, 0, count);
}

/**
 * Compares every element of `actual` with `expected` (and, past its length,
 * with POISON up to `actual.length`). Returns '' when equal, else a summary
 * of the number of mismatches and the first few.
 */
export function diff(actual: Uint32Array, expected: Uint32Array, what = 'element'): string {
  let bad = 0;
  const first: string[] = [];
  for (let i = 0; i < actual.length; i++) {
    const e = i < expected.length ? expected[i] : POISON;
    if (actual[i] !== e) {
      if (first.length < 5) first.push(`[${i}] ${actual[i]} != ${e}`);
      bad++;
    }
  }
  return bad === 0 ? '' : `${bad} of ${actual.length} ${what}s differ: ${first.join(', ')}`;
}

/** CPU exclusive scan (u32, wrapping) and total. */
export function cpuExclusiveScan(input: Uint32Array, n = input.length): { scan: Uint32Array; total: number } {
  const scan = new Uint32Array(n);
  let sum = 0;
  for (let i = 0; i < n; i++) {
    scan[i] = sum;
    sum = (sum + input[i]) >>> 0;
  }
  return { scan, total: sum };
}

/**
 * CPU stable sort by key (LSD radix, 8 bits per pass): the permutation of
 * indices. Descending sorts ~key ascending, which keeps equal keys in input
 * order, as the GPU sort does. Only the low `keyBits` bits count.
 */
export function cpuSortPermutation(keys: Uint32Array, n: number, descending: boolean, keyBits = 32): Uint32Array {
  const mask = keyBits >= 32 ? 0xffffffff : (1 << keyBits) >>> 0 ? ((1 << keyBits) - 1) >>> 0 : 0;
  const k = new Uint32Array(n);
  for (let i = 0; i < n; i++) k[i] = (descending ? ~keys[i] & mask : keys[i] & mask) >>> 0;
  let perm = new Uint32Array(n);
  for (let i = 0; i < n; i++) perm[i] = i;
  let tmp = new Uint32Array(n);
  const counts = new Uint32Array(256);
  for (let shift = 0; shift < keyBits; shift += 8) {
    counts.fill(0);
    for (let i = 0; i < n; i++) counts[(k[perm[i]] >>> shift) & 255]++;
    let sum = 0;
    for (let d = 0; d < 256; d++) {
      const c = counts[d];
      counts[d] = sum;
      sum += c;
    }
    for (let i = 0; i < n; i++) tmp[counts[(k[perm[i]] >>> shift) & 255]++] = perm[i];
    [perm, tmp] = [tmp, perm];
  }
  return perm;
}
