// A real WGSL kernel on the test device: every invocation of a 2D-gridded
// dispatch marks its linear index, and each index below the count must be
// marked exactly once (also past 65535 workgroups, where the grid is 2D).
import { describe, expect } from 'vitest';
import { gridSnippet, grid2d } from '../../../src/gpu/dispatch.ts';
import { createComputePipeline } from '../../../src/gpu/wgsl.ts';
import { readU32 } from '../../../src/gpu/buffers.ts';
import { gpuTest } from '../../helpers/gpu.ts';

const markKernel = {
  name: 'test/mark.wgsl',
  code: /* wgsl */ `
@group(0) @binding(0) var<storage, read_write> hits: array<atomic<u32>>;
@group(0) @binding(1) var<uniform> count: u32;
@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
        @builtin(local_invocation_index) lid: u32) {
  let i = linear_workgroup_index(wid, nwg) * 64u + lid;
  if (i < count) { atomicAdd(&hits[i], 1u); }
}`,
};

describe('grid2d', () => {
  gpuTest.for([1, 63, 64, 65, 65535 * 64, 65535 * 64 + 1, 2 * 65535 * 64 + 65])('covers %i invocations exactly once', async (count, { gpu }) => {
    const { device } = gpu;
    const pipeline = await createComputePipeline(device, 'test.mark', [gridSnippet, markKernel], 'main');
    const hits = device.createBuffer({ size: count * 4, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC });
    const uniform = device.createBuffer({ size: 4, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
    device.queue.writeBuffer(uniform, 0, new Uint32Array([count]));
    const bind = device.createBindGroup({
      layout: pipeline.getBindGroupLayout(0),
      entries: [{ binding: 0, resource: { buffer: hits } }, { binding: 1, resource: { buffer: uniform } }],
    });
    const [x, y] = grid2d(Math.ceil(count / 64));
    expect(x).toBeLessThanOrEqual(65535);
    const encoder = device.createCommandEncoder();
    const pass = encoder.beginComputePass();
    pass.setPipeline(pipeline);
    pass.setBindGroup(0, bind);
    pass.dispatchWorkgroups(x, y);
    pass.end();
    device.queue.submit([encoder.finish()]);
    const result = await readU32(device, hits);
    let wrong = 0;
    for (let i = 0; i < count; i++) if (result[i] !== 1) wrong++;
    expect(wrong).toBe(0);
    hits.destroy();
    uniform.destroy();
  });
});
