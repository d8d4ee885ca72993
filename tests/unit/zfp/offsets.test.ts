// 64-bit bit offsets: the WGSL block_start (u64 product of the block index in
// the shard and the block size, plus the shard's bit base) against BigInt, for
// offsets far past 2^32 bits; and shard plans of streams of 2^32 - 1 blocks
// (no allocation) against BigInt arithmetic.
import { describe, expect, it } from 'vitest';
import { readU32 } from '../../../src/gpu/buffers.ts';
import { createComputePipeline } from '../../../src/gpu/pipeline-cache.ts';
import { planShards, streamBindGroupLayout } from '../../../src/zfp/gpu-stream.ts';
import { zfpWgsl } from '../../../src/zfp/wgsl.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { rng } from './vectors.ts';

const probe = {
  name: 'test/block_start_probe.wgsl',
  code: /* wgsl */ `
@group(1) @binding(0) var<storage, read> probe_blocks: array<u32>;
@group(1) @binding(1) var<storage, read_write> probe_out: array<u32>;
@compute @workgroup_size(64)
fn probe(@builtin(global_invocation_id) id: vec3u) {
  let i = id.x;
  if (i >= arrayLength(&probe_blocks)) { return; }
  let s = block_start(probe_blocks[i]);
  let p = u64_mul(probe_blocks[i], probe_blocks[i] ^ 0x9e3779b9u);
  probe_out[4u * i] = s.x;
  probe_out[4u * i + 1u] = s.y;
  probe_out[4u * i + 2u] = p.x;
  probe_out[4u * i + 3u] = p.y;
}`,
};

describe('64-bit bit offsets', () => {
  gpuTest('block_start and u64_mul match BigInt past 2^32 bits', async ({ gpu }) => {
    const { device } = gpu;
    // zfpWgsl.decodeBlocks[0..3] = grid, u64, stream, stream_address (block_start)
    const parts = [...zfpWgsl.decodeBlocks.slice(0, 4), probe];
    const group1 = device.createBindGroupLayout({
      entries: [
        { binding: 0, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'read-only-storage' } },
        { binding: 1, visibility: GPUShaderStage.COMPUTE, buffer: { type: 'storage' } },
      ],
    });
    const layout = device.createPipelineLayout({ bindGroupLayouts: [streamBindGroupLayout(device), group1] });
    const pipeline = await createComputePipeline(device, 'test.blockStart', parts, 'probe', { layout });
    const random = rng(5);
    const first = 3_000_000_000;
    const bpb = 2047;
    const bitBase = 29;
    // blocks of a shard starting at `first`, up to 2^24 blocks in (2^35 bits: a 4 GiB shard)
    const blocks = Uint32Array.from(
      { length: 256 },
      (_, i) => first + (i < 4 ? [0, 1, 2 ** 24 - 1, 2 ** 21 + 3][i] : Math.floor(random() * 2 ** 24)),
    );
    const params = new Uint32Array(12);
    params.set([100, 100, 100, bpb, 25, 25, 25, 0, first, first + 2 ** 24, bitBase, 0]);
    const usage = GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST;
    const words = device.createBuffer({ size: 16, usage });
    const uniform = device.createBuffer({ size: 48, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
    const input = device.createBuffer({ size: blocks.byteLength, usage });
    const output = device.createBuffer({ size: blocks.length * 16, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC });
    device.queue.writeBuffer(uniform, 0, params);
    device.queue.writeBuffer(input, 0, blocks);
    const encoder = device.createCommandEncoder();
    const pass = encoder.beginComputePass();
    pass.setPipeline(pipeline);
    pass.setBindGroup(
      0,
      device.createBindGroup({
        layout: streamBindGroupLayout(device),
        entries: [
          { binding: 0, resource: { buffer: words } },
          { binding: 1, resource: { buffer: uniform } },
        ],
      }),
    );
    pass.setBindGroup(
      1,
      device.createBindGroup({
        layout: group1,
        entries: [
          { binding: 0, resource: { buffer: input } },
          { binding: 1, resource: { buffer: output } },
        ],
      }),
    );
    pass.dispatchWorkgroups(blocks.length / 64);
    pass.end();
    device.queue.submit([encoder.finish()]);
    const got = await readU32(device, output);
    let past32 = 0;
    blocks.forEach((b, i) => {
      const bit = BigInt(b - first) * BigInt(bpb) + BigInt(bitBase);
      if (bit >= 2n ** 32n) past32++;
      expect([got[4 * i], got[4 * i + 1]], `block ${b}`).toEqual([Number(bit >> 5n), Number(bit & 31n)]);
      const product = BigInt(b) * BigInt((b ^ 0x9e3779b9) >>> 0);
      expect([got[4 * i + 2], got[4 * i + 3]], `u64_mul ${b}`).toEqual([Number(product & 0xffffffffn), Number(product >> 32n)]);
    });
    expect(past32).toBeGreaterThan(200);
    for (const b of [words, uniform, input, output]) b.destroy();
  });

  it('plans shards of a 2^32 - 1 block stream exactly', () => {
    for (const [bpb, payload] of [
      [2048, 96],
      [9, 148],
      [333, 0],
    ] as const) {
      const blockCount = 0xffffffff;
      const maxShardBytes = 1 << 30;
      const plans = planShards(
        { blockCount, bitsPerBlock: bpb, payloadBitOffset: payload, fileName: 'huge.zfp', dims: [1, 1, 1] },
        maxShardBytes,
      );
      let next = 0;
      for (const p of plans) {
        expect(p.firstBlock).toBe(next);
        const start = BigInt(payload) + BigInt(p.firstBlock) * BigInt(bpb);
        const end = BigInt(payload) + BigInt(p.endBlock) * BigInt(bpb);
        if (p.firstBlock > 0) expect(BigInt(p.firstWord)).toBe(start / 32n);
        expect(BigInt(p.bitBase)).toBe(start - 32n * BigInt(p.firstWord));
        expect(BigInt(p.firstWord + p.wordCount)).toBe((end + 31n) / 32n);
        expect((p.wordCount + 1) * 4).toBeLessThanOrEqual(maxShardBytes);
        next = p.endBlock;
      }
      expect(next).toBe(blockCount);
    }
  });
});
