// GPU fixture for unit tests: every test gets its own device on Dawn
// (SwiftShader here, a GPU where there is one), and fails if anything on it
// raises a validation, out-of-memory or internal error, captured or not.
import { test as base } from 'vitest';
import type { GpuFailure } from '../../src/gpu/device.ts';
import { requestNodeGpu } from '../../src/gpu/node-gpu.ts';
import { finishTestGpu, pushTestScopes, type TestGpu } from './gpu-scopes.ts';

export { finishTestGpu, type TestGpu };

/**
 * ZFPISO_TEST_LIMITS=default: devices get WebGPU's default limits instead of
 * the adapter's (SwiftShader's are far above a laptop GPU's), so sharding and
 * fallbacks run. `npm test` runs the isosurface and zfp tests both ways.
 */
export const testLimits: 'adapter' | 'default' = process.env.ZFPISO_TEST_LIMITS === 'default' ? 'default' : 'adapter';

/**
 * Whether this run is one of the suites that run a file again to change the
 * code path (`limits`: WebGPU's default limits; `gpukernels`: the GPU-shaped
 * kernels forced), not the data: a file may take its smallest case there,
 * since the `unit` suite has already run every case (tests/README.md).
 */
export const codePathRerun: boolean = testLimits === 'default' || (process.env.ZFPISO_KERNEL_PATH ?? '') === 'gpu';

/** Creates a device and starts error scopes; `finishTestGpu` checks them. */
export async function createTestGpu(): Promise<TestGpu> {
  const failures: GpuFailure[] = [];
  const ctx = await requestNodeGpu({ label: 'test.device', limits: testLimits, onFailure: (f) => failures.push(f) });
  if (testLimits === 'default' && ctx.limits.maxStorageBufferBindingSize > 128 * 2 ** 20) {
    throw new Error(`ZFPISO_TEST_LIMITS=default, yet the device allows ${ctx.limits.maxStorageBufferBindingSize} B storage bindings`);
  }
  pushTestScopes(ctx.device);
  return { ...ctx, failures };
}

/**
 * `gpuTest('name', async ({ gpu }) => ...)`: a vitest test with a fresh
 * device that fails on any WebGPU error raised during the test.
 */
export const gpuTest = base.extend<{ gpu: TestGpu }>({
  // eslint-disable-next-line no-empty-pattern
  gpu: async ({}, use) => {
    const gpu = await createTestGpu();
    let error: unknown;
    try {
      await use(gpu);
    } finally {
      try {
        await finishTestGpu(gpu);
      } catch (e) {
        error = e;
      }
    }
    if (error) throw error;
  },
});
