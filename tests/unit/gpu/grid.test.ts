// A real WGSL kernel on the test device: every invocation of a dispatch laid
// out by dispatchGrid (1D, 2D past the per-dimension limit, 3D past its
// square) marks its index from grid_invocation_index, and each index below
// the count must be marked exactly once. The limit is lowered to 7 and 300
// so that 3D grids happen at small counts.
import { describe, expect, test } from 'vitest';
import { readU32 } from '../../../src/gpu/buffers.ts';
import { dispatchGrid, dispatchWorkgroups, gridSnippet } from '../../../src/gpu/dispatch.ts';
import { createComputePipeline } from '../../../src/gpu/pipeline-cache.ts';
import { gpuTest } from '../../helpers/gpu.ts';

const markKernel = {
  name: 'test/mark.wgsl',
  code: /* wgsl */ `
@group(0) @binding(0) var<storage, read_write> hits: array<atomic<u32>>;
@group(0) @binding(1) var<uniform> count: u32;
@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u,
        @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, 64u);
  if (i < count) { atomicAdd(&hits[i], 1u); }
}`,
};

describe('dispatchGrid', () => {
  test('covers the workgroups within the limit: 1D, then 2D, then 3D', () => {
    for (const max of [1, 2, 7, 300, 65535]) {
      for (const w of [1, 2, max - 1, max, max + 1, max * max - 1, max * max, max * max + 1, 3 * max * max + 5, 65535 * 64 + 1]) {
        if (w < 1 || w > max ** 3) continue;
        const [x, y, z] = dispatchGrid(w, max);
        expect(x * y * z, `${w} @ ${max}`).toBeGreaterThanOrEqual(w);
        expect(Math.max(x, y, z), `${w} @ ${max}`).toBeLessThanOrEqual(max);
        // Overshoot: less than one row (2D) or one plane (3D) of workgroups.
        expect(x * y * z - w, `${w} @ ${max}`).toBeLessThan(z > 1 ? x * y : y > 1 ? x : 1);
        if (w <= max) expect([x, y, z]).toEqual([w, 1, 1]);
        else if (w <= max * max) expect(z).toBe(1);
        else expect(z).toBeGreaterThan(1);
      }
    }
    expect(dispatchGrid(0, 7)).toEqual([0, 1, 1]);
  });
});

describe('grid_invocation_index', () => {
  gpuTest.for([
    [1, 65535],
    [63, 65535],
    [65, 65535],
    [65535 * 64, 65535],
    [65535 * 64 + 1, 65535],
    [2 * 65535 * 64 + 65, 65535],
    [7 * 7 * 64 + 1, 7],
    [3 * 7 * 7 * 64 + 100, 7],
    [300 * 300 * 64 + 64 * 301 + 3, 300],
  ] as const)('covers %i invocations exactly once (limit %i)', async ([count, max], { gpu }) => {
    const { device } = gpu;
    const pipeline = await createComputePipeline(device, 'test.mark', [gridSnippet, markKernel], 'main');
    const hits = device.createBuffer({ size: count * 4, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC });
    const uniform = device.createBuffer({ size: 4, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
    device.queue.writeBuffer(uniform, 0, new Uint32Array([count]));
    const bind = device.createBindGroup({
      layout: pipeline.getBindGroupLayout(0),
      entries: [
        { binding: 0, resource: { buffer: hits } },
        { binding: 1, resource: { buffer: uniform } },
      ],
    });
    const encoder = device.createCommandEncoder();
    const pass = encoder.beginComputePass();
    pass.setPipeline(pipeline);
    pass.setBindGroup(0, bind);
    dispatchWorkgroups(pass, Math.ceil(count / 64), max);
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
