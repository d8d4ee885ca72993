// The compressed vertex format: the WGSL encode/decode (vertex_format.wgsl,
// what the kernel writes and the renderer reads) against the TS twin
// (vertex-format.ts), and the layout constants shared by TS and WGSL.
import { readFileSync } from 'node:fs';
import { describe, expect, test } from 'vitest';
import { readF32, readU32 } from '../../../src/gpu/buffers.ts';
import { createComputePipeline } from '../../../src/gpu/pipeline-cache.ts';
import { A, C, NONE, S, SHARD_RECORD_BYTES, STATUS_CACHE_SHORTFALL, STATUS_VERTEX_OVERFLOW } from '../../../src/isosurface/layout.ts';
import { decodeVertices, encodeVertexPosition, VERTEX_QUANTUM } from '../../../src/isosurface/vertex-format.ts';
import { vertexFormatSnippet } from '../../../src/isosurface/wgsl.ts';
import type { Dims } from '../../../src/core/naming.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { rng } from '../mc/reference.ts';

describe('vertex format', () => {
  test('TS encode/decode: 10 bits per axis, block origin + q * 4 / 1023', () => {
    const info = { blockGrid: [3, 5, 2] as Dims };
    const random = rng(3);
    const packed = new Uint32Array(2 * 1000);
    const expected: number[] = [];
    for (let v = 0; v < 1000; v++) {
      const local: [number, number, number] = [random() * 4, random() * 4, random() * 4];
      if (v === 0) local.splice(0, 3, 0, 4, 2);
      const block = Math.floor(random() * 30);
      packed[2 * v] = encodeVertexPosition(local);
      packed[2 * v + 1] = block;
      const origin = [4 * (block % 3), 4 * (Math.floor(block / 3) % 5), 4 * Math.floor(block / 15)];
      for (let a = 0; a < 3; a++) expected.push(origin[a] + local[a]);
    }
    expect(packed[0]).toBe(0 | (1023 << 10) | (512 << 20)); // 2 * 255.75 = 511.5: to even
    const decoded = decodeVertices(packed, 1000, info);
    for (let i = 0; i < expected.length; i++) expect(Math.abs(decoded[i] - expected[i])).toBeLessThanOrEqual(VERTEX_QUANTUM / 2 + 1e-5);
  });

  gpuTest('WGSL encode_vertex_position / decode_vertex_position = the TS twin', async ({ gpu }) => {
    const { device } = gpu;
    const n = 4096;
    const grid: Dims = [7, 3, 11];
    const random = rng(9);
    const locals = new Float32Array(4 * n);
    const ids = new Uint32Array(n);
    for (let v = 0; v < n; v++) {
      for (let a = 0; a < 3; a++) locals[4 * v + a] = v < 8 ? [0, 4, 2, 1.0019550323486328][v % 4] : random() * 4;
      ids[v] = Math.floor(random() * grid[0] * grid[1] * grid[2]);
    }
    const pipeline = await createComputePipeline(
      device,
      'test.vertexFormat',
      [
        vertexFormatSnippet,
        {
          name: 'test/vertex_format.wgsl',
          code: /* wgsl */ `
@group(0) @binding(0) var<storage, read> locals: array<vec4f>;
@group(0) @binding(1) var<storage, read> ids: array<u32>;
@group(0) @binding(2) var<storage, read_write> packed: array<u32>;
@group(0) @binding(3) var<storage, read_write> decoded: array<vec4f>;
@compute @workgroup_size(64) fn main(@builtin(global_invocation_id) id: vec3u) {
  let v = id.x;
  if (v >= arrayLength(&ids)) { return; }
  let p = encode_vertex_position(locals[v].xyz);
  packed[v] = p;
  decoded[v] = vec4f(decode_vertex_position(p, ids[v], vec3u(${grid.join('u, ')}u)), 0.0);
}`,
        },
      ],
      'main',
    );
    const make = (data: ArrayBufferView | number) => {
      const size = typeof data === 'number' ? data : data.byteLength;
      const b = device.createBuffer({ size, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST });
      if (typeof data !== 'number') device.queue.writeBuffer(b, 0, data as BufferSource);
      return b;
    };
    const buffers = [make(locals), make(ids), make(4 * n), make(16 * n)];
    const encoder = device.createCommandEncoder();
    const pass = encoder.beginComputePass();
    pass.setPipeline(pipeline);
    pass.setBindGroup(
      0,
      device.createBindGroup({
        layout: pipeline.getBindGroupLayout(0),
        entries: buffers.map((buffer, binding) => ({ binding, resource: { buffer } })),
      }),
    );
    pass.dispatchWorkgroups(n / 64);
    pass.end();
    device.queue.submit([encoder.finish()]);
    const gpuPacked = await readU32(device, buffers[2]);
    const gpuDecoded = await readF32(device, buffers[3]);
    const pairs = new Uint32Array(2 * n);
    let differentQ = 0;
    for (let v = 0; v < n; v++) {
      const tsPacked = encodeVertexPosition([locals[4 * v], locals[4 * v + 1], locals[4 * v + 2]]);
      if (tsPacked !== gpuPacked[v]) differentQ++;
      pairs[2 * v] = gpuPacked[v];
      pairs[2 * v + 1] = ids[v];
    }
    expect(differentQ).toBe(0);
    const tsDecoded = decodeVertices(pairs, n, { blockGrid: grid });
    for (let v = 0; v < n; v++) {
      for (let a = 0; a < 3; a++) expect(Math.abs(gpuDecoded[4 * v + a] - tsDecoded[3 * v + a])).toBeLessThan(1e-5);
    }
  });

  test('the counters layout in common.wgsl is the one in layout.ts', () => {
    const wgsl = readFileSync(new URL('../../../shaders/isosurface/common.wgsl', import.meta.url), 'utf8');
    const constants = new Map<string, number>();
    for (const m of wgsl.matchAll(/^const (\w+): u32 = (0x[0-9a-f]+|\d+)u;/gm)) constants.set(m[1], Number(m[2]));
    const snake = (s: string) => s.replace(/[A-Z]/g, (c) => `_${c}`).toUpperCase();
    for (const [name, word] of Object.entries(C)) expect(constants.get(`C_${snake(name)}`), name).toBe(word);
    for (const [name, word] of Object.entries(A)) expect(constants.get(`A_${snake(name)}`), name).toBe(word);
    for (const [name, word] of Object.entries(S)) expect(constants.get(`S_${snake(name)}`), name).toBe(word);
    expect(constants.get('SHARD_STRIDE')! * 4).toBe(SHARD_RECORD_BYTES);
    expect(constants.get('NONE')).toBe(NONE);
    expect(constants.get('STATUS_CACHE_SHORTFALL')).toBe(STATUS_CACHE_SHORTFALL);
    expect(constants.get('STATUS_VERTEX_OVERFLOW')).toBe(STATUS_VERTEX_OVERFLOW);
    const words = [...constants.entries()].filter(([k]) => k.startsWith('C_')).length;
    expect(words).toBe(Object.keys(C).length);
  });
});
