// tests/helpers/gpu.ts for the wgpu run: the same fixture (a fresh device per
// test, failing on any WebGPU error), on the runtime's own navigator.gpu
// (Deno: wgpu) instead of Dawn.
import { requestGpu, type GpuFailure } from '../../src/gpu/device.ts';
import { finishTestGpu, pushTestScopes, type TestGpu } from '../helpers/gpu-scopes.ts';
import { formatName, test } from './vitest-shim.ts';

export { finishTestGpu, type TestGpu };
export const testLimits: 'adapter' | 'default' = 'adapter';
/**
 * The wgpu run is a rerun for another implementation and shader compiler:
 * files that take their smallest case in reruns (tests/helpers/gpu.ts) do
 * here too (every kernel still runs; the unit suite has the large sizes).
 */
export const codePathRerun = true;

export async function createTestGpu(): Promise<TestGpu> {
  const failures: GpuFailure[] = [];
  const ctx = await requestGpu(navigator.gpu, { label: 'test.device', onFailure: (f) => failures.push(f) });
  pushTestScopes(ctx.device);
  return { ...ctx, failures };
}

export function gpuTest(name: string, fn: (ctx: { gpu: TestGpu }) => unknown | Promise<unknown>, timeoutMs?: number): void {
  test(
    name,
    async () => {
      const gpu = await createTestGpu();
      let error: unknown;
      try {
        await fn({ gpu });
      } catch (e) {
        error = e;
      }
      try {
        await finishTestGpu(gpu);
      } catch (e) {
        error ??= e;
      }
      if (error) throw error;
    },
    timeoutMs,
  );
}

/** `gpuTest.for(cases)(name, (case, { gpu }) => ...)` */
gpuTest.for =
  <T>(cases: readonly T[]) =>
  (name: string, fn: (c: T, ctx: { gpu: TestGpu }) => unknown, timeoutMs?: number) => {
    for (const c of cases) gpuTest(formatName(name, c), (ctx) => fn(c, ctx), timeoutMs);
  };
