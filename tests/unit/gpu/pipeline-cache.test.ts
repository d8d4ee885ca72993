// The per-device pipeline cache (src/gpu/pipeline-cache.ts) and the keyed
// caches (src/gpu/bind-group-cache.ts): what is shared, what is not, and that
// a failed compilation is not kept.
import { describe, expect, it, test } from 'vitest';
import { BindGroupCache, KeyedCache } from '../../../src/gpu/bind-group-cache.ts';
import { bindGroupLayout, createComputePipeline, pipelineCacheSize } from '../../../src/gpu/pipeline-cache.ts';
import { WgslCompileError } from '../../../src/gpu/wgsl.ts';
import { countCompilations } from '../../helpers/count-compilations.ts';
import { createTestGpu, finishTestGpu, gpuTest } from '../../helpers/gpu.ts';

const kernel = {
  name: 'test/fill.wgsl',
  code: /* wgsl */ `
override VALUE: u32 = 1u;
@group(0) @binding(0) var<storage, read_write> out: array<u32>;
@compute @workgroup_size(1) fn fill() { out[0] = VALUE; }
@compute @workgroup_size(1) fn fill_twice() { out[0] = 2u * VALUE; }`,
};

describe('createComputePipeline (per-device cache)', () => {
  gpuTest('the same request gives the same pipeline; constants, entry point and layout tell pipelines apart', async ({ gpu }) => {
    const { device } = gpu;
    const layout = bindGroupLayout(device, 'test.layout', [
      { binding: 0, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'storage' } },
    ]);
    expect(
      bindGroupLayout(device, 'test.other-label', [{ visibility: GPUShaderStage.COMPUTE, buffer: { type: 'storage' }, binding: 0 }]),
    ).toBe(layout);
    const count = countCompilations(device);
    try {
      const [a, b] = await Promise.all([
        createComputePipeline(device, 'test.a', [kernel], 'fill', { constants: { VALUE: 3 } }),
        createComputePipeline(device, 'test.b', [kernel], 'fill', { constants: { VALUE: 3 } }),
      ]);
      expect(b).toBe(a);
      expect(count).toMatchObject({ modules: 1, pipelines: 1 });
      const others = await Promise.all([
        createComputePipeline(device, 'test.c', [kernel], 'fill', { constants: { VALUE: 4 } }),
        createComputePipeline(device, 'test.d', [kernel], 'fill_twice', { constants: { VALUE: 3 } }),
        createComputePipeline(device, 'test.e', [kernel], 'fill', { constants: { VALUE: 3 }, layout: [layout] }),
      ]);
      expect(new Set([a, ...others]).size).toBe(4);
      expect(count).toMatchObject({ modules: 1, pipelines: 4 });
      expect(await createComputePipeline(device, 'test.f', [kernel], 'fill', { constants: { VALUE: 3 }, layout: [layout] })).toBe(
        others[2],
      );
      expect(count.pipelines).toBe(4);
      expect(pipelineCacheSize(device)).toMatchObject({ modules: 1, pipelines: 4 });
    } finally {
      count.restore();
    }
    // Each pipeline runs with its own constants.
    const out = device.createBuffer({ size: 16, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC });
    const staging = device.createBuffer({ size: 16, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
    const encoder = device.createCommandEncoder();
    const p4 = await createComputePipeline(device, 'test.c', [kernel], 'fill', { constants: { VALUE: 4 } });
    const pass = encoder.beginComputePass();
    pass.setPipeline(p4);
    pass.setBindGroup(
      0,
      device.createBindGroup({ layout: p4.getBindGroupLayout(0), entries: [{ binding: 0, resource: { buffer: out } }] }),
    );
    pass.dispatchWorkgroups(1);
    pass.end();
    encoder.copyBufferToBuffer(out, 0, staging, 0, 16);
    device.queue.submit([encoder.finish()]);
    await staging.mapAsync(GPUMapMode.READ);
    expect(new Uint32Array(staging.getMappedRange())[0]).toBe(4);
    staging.unmap();
  });

  it('a WGSL error rejects every request and is not cached', async () => {
    const gpu = await createTestGpu();
    const broken = [{ name: 'test/broken.wgsl', code: '@compute @workgroup_size(1) fn main() { let x = undefined_thing; }' }];
    const count = countCompilations(gpu.device);
    try {
      await expect(createComputePipeline(gpu.device, 'test.broken', broken, 'main')).rejects.toBeInstanceOf(WgslCompileError);
      await expect(createComputePipeline(gpu.device, 'test.broken', broken, 'main')).rejects.toBeInstanceOf(WgslCompileError);
      expect(count.modules).toBe(2);
      expect(pipelineCacheSize(gpu.device)).toMatchObject({ modules: 0, pipelines: 0 });
    } finally {
      count.restore();
    }
    // The invalid modules also raised validation errors on the device.
    await expect(finishTestGpu(gpu)).rejects.toThrow(/WebGPU error/);
  });
});

describe('KeyedCache / BindGroupCache', () => {
  test('tuples of objects and numbers, buffer ranges by buffer, offset and size; a limit empties it', () => {
    const cache = new KeyedCache<string>(4);
    const a = {};
    const b = {};
    let made = 0;
    const make = (v: string) => () => {
      made++;
      return v;
    };
    expect(cache.key(a).key(1).get(make('a1'))).toBe('a1');
    expect(cache.key(a).key(1).get(make('other'))).toBe('a1');
    expect(cache.key(a).key(2).get(make('a2'))).toBe('a2');
    expect(cache.key(b).key(1).get(make('b1'))).toBe('b1');
    expect(cache.get([a, 1], make('other'))).toBe('a1');
    expect(made).toBe(3);
    const buffer = { mapState: 'unmapped' } as unknown as GPUBuffer;
    expect(cache.ref(buffer).get(make('whole'))).toBe('whole');
    expect(cache.ref({ buffer }).get(make('other'))).toBe('whole');
    expect(made).toBe(4);
    // A fifth value passes the limit: the cache starts empty again.
    expect(cache.ref({ buffer, offset: 256, size: 16 }).get(make('range'))).toBe('range');
    expect(cache.key(a).key(1).get(make('again'))).toBe('again');
    const groups = new BindGroupCache();
    expect(groups.key(a).get(() => 'x' as unknown as GPUBindGroup)).toBe('x');
  });
});
