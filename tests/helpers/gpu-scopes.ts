// The error-scope half of the GPU test fixture, shared by tests/helpers/gpu.ts
// (Dawn in Node) and tests/wgpu/gpu.ts (wgpu in Deno): no runtime imports, so
// it bundles for either.
import type { GpuContext, GpuFailure } from '../../src/gpu/device.ts';

export interface TestGpu extends GpuContext {
  /** Errors seen so far (uncaptured errors and device loss). */
  failures: GpuFailure[];
}

const SCOPES: GPUErrorFilter[] = ['validation', 'out-of-memory', 'internal'];

/** Starts one error scope per filter on a new device; `finishTestGpu` pops them. */
export function pushTestScopes(device: GPUDevice): void {
  for (const filter of SCOPES) device.pushErrorScope(filter);
}

/** Waits for the queue, pops the scopes and destroys the device; throws on any error. */
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
