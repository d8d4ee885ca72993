// tests/helpers/gpu.ts for the wgpu run: the same fixture (a fresh device per
// test, failing on any WebGPU error), on the runtime's own navigator.gpu
// (Deno: wgpu) instead of Dawn.
import { requestGpu, type GpuContext, type GpuFailure } from '../../src/gpu/device.ts';
import { formatName, test } from './vitest-shim.ts';

export interface TestGpu extends GpuContext {
  failures: GpuFailure[];
}

const SCOPES: GPUErrorFilter[] = ['validation', 'out-of-memory', 'internal'];
export const testLimits: 'adapter' | 'default' = 'adapter';

export async function createTestGpu(): Promise<TestGpu> {
  const failures: GpuFailure[] = [];
  const ctx = await requestGpu(navigator.gpu, { label: 'test.device', onFailure: (f) => failures.push(f) });
  for (const filter of SCOPES) ctx.device.pushErrorScope(filter);
  return { ...ctx, failures };
}

export async function finishTestGpu(gpu: TestGpu): Promise<void> {
  const { device } = gpu;
  await device.queue.onSubmittedWorkDone();
  const scoped: (GPUError | null)[] = [];
  for (let i = 0; i < SCOPES.length; i++) scoped.push(await device.popErrorScope());
  device.destroy();
  const messages = [
    ...scoped.filter((e): e is GPUError => e !== null).map((e) => `WebGPU error: ${e.message}`),
    ...gpu.failures.map((f) => `WebGPU ${f.kind}: ${f.message}`),
  ];
  if (messages.length > 0) throw new Error(messages.join('\n'));
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
gpuTest.for = <T>(cases: readonly T[]) => (name: string, fn: (c: T, ctx: { gpu: TestGpu }) => unknown, timeoutMs?: number) => {
  for (const c of cases) gpuTest(formatName(name, c), (ctx) => fn(c, ctx), timeoutMs);
};
