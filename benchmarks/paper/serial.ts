// Serial marching cubes in Node: the C++ twin compiled natively (g++ -O3,
// benchmarks/serial-mc/build.mjs, timed inside the binary), the same C++ in
// WebAssembly, and the TypeScript version, one surface per isovalue each.
import { execFileSync } from 'node:child_process';
import { join } from 'node:path';
import { timeSerialMc, type SerialTimes } from '../../src/examples/paper-bench/measure.ts';
import type { PreparedVolume } from './volumes.ts';

export interface SerialNodeResult {
  isovalues: number[];
  native?: SerialTimes;
  nativeError?: string;
  wasm: SerialTimes;
  js: SerialTimes;
}

/** Builds the native binary if needed (g++), or says why it cannot. */
export function nativeBinary(root: string): { path?: string; error?: string; compiler?: string } {
  try {
    const out = execFileSync(process.execPath, [join(root, 'benchmarks', 'serial-mc', 'build.mjs'), 'native', '--if-stale'], {
      encoding: 'utf8',
      stdio: ['ignore', 'pipe', 'pipe'],
    });
    let compiler = '';
    try {
      compiler = execFileSync(process.env.CXX || 'g++', ['--version'], { encoding: 'utf8' }).split('\n')[0];
    } catch {
      /* reported by the build already */
    }
    return { path: out.trim().split('\n').pop(), compiler };
  } catch (e) {
    const err = e as { stderr?: string; message: string };
    return { error: (err.stderr || err.message).trim().split('\n').slice(-3).join(' ') };
  }
}

export function runNative(binary: string, v: PreparedVolume, isovalues: number[]): SerialTimes {
  const out = execFileSync(binary, [v.rawPath, ...v.dims.map(String), isovalues.map(String).join(','), '--repeat', '1'], {
    encoding: 'utf8',
    maxBuffer: 1 << 26,
  });
  const answer = JSON.parse(out) as { results: { iso: number; triangles: number; ms: number[] }[] };
  return { ms: answer.results.map((r) => r.ms[0]), triangles: answer.results.map((r) => r.triangles) };
}

export async function runSerialNode(
  v: PreparedVolume,
  isovalues: number[],
  binary: string | undefined,
  nativeError: string | undefined,
): Promise<SerialNodeResult> {
  let native: SerialTimes | undefined;
  let error = nativeError;
  if (binary) {
    try {
      native = runNative(binary, v, isovalues);
    } catch (e) {
      error = (e as Error).message.split('\n')[0];
    }
  }
  const t = await timeSerialMc(v.values, v.dims, isovalues, ['js', 'wasm']);
  if (native) {
    const bad = native.triangles.findIndex((n, i) => n !== t.js!.triangles[i]);
    if (bad >= 0)
      throw new Error(`${v.label}: native MC gave ${native.triangles[bad]} triangles at iso ${isovalues[bad]}, TS ${t.js!.triangles[bad]}`);
  }
  return { isovalues, native, nativeError: error, wasm: t.wasm!, js: t.js! };
}
