// The harness must turn WebGPU errors into failures with the message.
import { describe, expect, it } from 'vitest';
import { spawnSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { createShaderModule, WgslCompileError } from '../../../src/gpu/wgsl.ts';
import { createTestGpu, finishTestGpu } from '../../helpers/gpu.ts';

describe('GPU error reporting', () => {
  it('a WGSL error rejects with the compiler message, file and line', async () => {
    const gpu = await createTestGpu();
    const parts = [
      { name: 'shaders/ok.wgsl', code: 'fn ok() -> u32 { return 1u; }' },
      { name: 'shaders/broken.wgsl', code: 'fn f() -> u32 {\n  return undefined_thing;\n}' },
    ];
    const error = await createShaderModule(gpu.device, 'test.broken', parts).catch((e: unknown) => e);
    expect(error).toBeInstanceOf(WgslCompileError);
    expect((error as Error).message).toMatch(/shaders\/broken\.wgsl:2:/);
    expect((error as Error).message).toMatch(/undefined_thing/);
    // The invalid module also raised a validation error on the device.
    await expect(finishTestGpu(gpu)).rejects.toThrow(/WebGPU error/);
  });

  it('a validation error makes the fixture throw with its message', async () => {
    const gpu = await createTestGpu();
    // A uniform binding to a buffer without UNIFORM usage is invalid.
    const buffer = gpu.device.createBuffer({ label: 'notUniform', size: 16, usage: GPUBufferUsage.STORAGE });
    const layout = gpu.device.createBindGroupLayout({
      entries: [{ binding: 0, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'uniform' } }],
    });
    gpu.device.createBindGroup({ layout, entries: [{ binding: 0, resource: { buffer } }] });
    await expect(finishTestGpu(gpu)).rejects.toThrow(/notUniform/);
  });

  it('a test with an injected error fails under vitest, showing the message', () => {
    const root = fileURLToPath(new URL('../../..', import.meta.url));
    const run = spawnSync(
      process.execPath,
      ['node_modules/vitest/vitest.mjs', 'run', '--config', 'tests/fixtures/injected-errors/vitest.config.ts'],
      { cwd: root, encoding: 'utf8', env: { ...process.env, FORCE_COLOR: '0' } },
    );
    const output = run.stdout + run.stderr;
    expect(run.status, output).not.toBe(0);
    expect(output).toMatch(/2 failed/);
    expect(output).toMatch(/injectedWgslError|unknown identifier|unresolved/i);
    expect(output).toMatch(/wrongUsageBuffer/);
  }, 120_000);
});
