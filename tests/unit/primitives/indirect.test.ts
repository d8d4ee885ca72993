// IndirectArgs: (x, y, z) from a GPU-side count, 2D past the per-dimension
// limit, checked against the host grid and by a real indirect dispatch that
// must mark each index below the count exactly once.
import { describe, expect } from 'vitest';
import { dispatchGrid, gridSnippet } from '../../../src/gpu/dispatch.ts';
import { createComputePipeline } from '../../../src/gpu/pipeline-cache.ts';
import { IndirectArgs } from '../../../src/primitives/indirect.ts';
import { ExclusiveScan } from '../../../src/primitives/scan.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { POISON, gpuCount, randomMask, read, upload } from './helpers.ts';

// The host twin of dispatch_grid (shaders/common/grid.wgsl): 3D past maxPerDim^2 workgroups.
function expectedArgs(count: number, items: number, maxPerDim: number): number[] {
  return dispatchGrid(Math.ceil(count / items), maxPerDim);
}

describe('IndirectArgs', () => {
  gpuTest('arguments for counts up to 2^32 - 1, 1D and 2D', async ({ gpu }) => {
    const { device } = gpu;
    const problems: string[] = [];
    for (const [items, maxPerDim] of [
      [256, 65535],
      [64, 65535],
      [1, 65535],
      [5, 7],
    ]) {
      const args = await IndirectArgs.create(device, { itemsPerWorkgroup: items, maxWorkgroupsPerDimension: maxPerDim });
      const counts = [0, 1, items - 1, items, items + 1, 65535 * items, 65535 * items + 1, 2 ** 24, 2 ** 27 + 5, 2 ** 32 - 1].filter(
        (c) => c >= 0,
      );
      const out = upload(
        device,
        'test.args',
        new Uint32Array(0),
        3 * counts.length + 1,
        GPUBufferUsage.STORAGE | GPUBufferUsage.INDIRECT | GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST,
      );
      const countBufs = counts.map((c) => gpuCount(device, c, 4));
      const encoder = device.createCommandEncoder();
      counts.forEach((_, i) => args.encode(encoder, { count: countBufs[i], out: { buffer: out, offset: 4 + 12 * i } }));
      device.queue.submit([encoder.finish()]);
      const got = await read(device, out);
      if (got[0] !== POISON) problems.push(`items ${items}: word 0 overwritten`);
      counts.forEach((c, i) => {
        const want = expectedArgs(c, items, maxPerDim);
        const have = [...got.subarray(1 + 3 * i, 4 + 3 * i)];
        const [x, y, z] = have;
        if (have.join() !== want.join()) problems.push(`items ${items} count ${c}: [${have}] != [${want}]`);
        if (x > maxPerDim || y > maxPerDim) problems.push(`items ${items} count ${c}: over the limit`);
        if (x * y * z < Math.ceil(c / items)) problems.push(`items ${items} count ${c}: too few workgroups`);
      });
      args.destroy();
    }
    expect(problems).toEqual([]);
  });

  gpuTest('a count written by a kernel drives an indirect 2D dispatch covering each index once', async ({ gpu }) => {
    const { device } = gpu;
    // 65535 * 64 + 100 ones: the ExclusiveScan total, then 65537 workgroups of 64.
    const ones = 65535 * 64 + 100;
    const n = ones + 1000;
    const mask = randomMask(n, 1, 1);
    mask.fill(0, ones);
    const maskBuf = upload(device, 'test.mask', mask);
    const scanned = upload(device, 'test.scanned', new Uint32Array(0), n);
    const state = upload(
      device,
      'test.state',
      new Uint32Array(0),
      4,
      GPUBufferUsage.STORAGE | GPUBufferUsage.INDIRECT | GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST,
    );
    const hits = upload(device, 'test.hits', new Uint32Array(n));
    const scan = await ExclusiveScan.create(device, { capacity: n });
    const args = await IndirectArgs.create(device, { itemsPerWorkgroup: 64 });
    const mark = await createComputePipeline(
      device,
      'test.mark',
      [
        gridSnippet,
        {
          name: 'test/mark.wgsl',
          code: /* wgsl */ `
@group(0) @binding(0) var<storage, read_write> hits: array<atomic<u32>>;
@group(0) @binding(1) var<storage, read> state: array<u32>;
@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wid: vec3u, @builtin(num_workgroups) nwg: vec3u, @builtin(local_invocation_index) lid: u32) {
  let i = grid_invocation_index(wid, nwg, lid, 64u);
  if (i < state[0]) { atomicAdd(&hits[i], 1u); }
}`,
        },
      ],
      'main',
    );
    const bind = device.createBindGroup({
      layout: mark.getBindGroupLayout(0),
      entries: [
        { binding: 0, resource: { buffer: hits } },
        { binding: 1, resource: { buffer: state, size: 4 } },
      ],
    });
    const encoder = device.createCommandEncoder();
    scan.encode(encoder, { input: maskBuf, output: scanned, count: n, totalOut: { buffer: state, offset: 0 } });
    args.encode(encoder, { count: { buffer: state, offset: 0 }, out: { buffer: state, offset: 4 } });
    const pass = encoder.beginComputePass();
    pass.setPipeline(mark);
    pass.setBindGroup(0, bind);
    pass.dispatchWorkgroupsIndirect(state, 4);
    pass.end();
    device.queue.submit([encoder.finish()]);
    const s = await read(device, state);
    expect([...s.subarray(0, 4)]).toEqual([ones, ...dispatchGrid(Math.ceil(ones / 64))]);
    expect(s[2]).toBeGreaterThan(1);
    const h = await read(device, hits);
    let wrong = 0;
    for (let i = 0; i < n; i++) if (h[i] !== (i < ones ? 1 : 0)) wrong++;
    expect(wrong).toBe(0);
    scan.destroy();
    args.destroy();
  });
});
