// The compressed vertex format: the WGSL encode/decode (vertex_format.wgsl,
// what the kernel writes and the renderer reads) against the TS twin
// (vertex-format.ts), up to the largest block coordinates, and the layout
// constants shared by TS and WGSL.
import { readFileSync } from 'node:fs';
import { describe, expect, test } from 'vitest';
import { readF32, readU32 } from '../../../src/gpu/buffers.ts';
import { createComputePipeline } from '../../../src/gpu/pipeline-cache.ts';
import { A, C, NONE, S, SHARD_RECORD_BYTES, STATUS_CACHE_SHORTFALL, STATUS_VERTEX_OVERFLOW } from '../../../src/isosurface/layout.ts';
import { decodeVertices, encodeVertexEdge, MAX_VERTEX_VOXELS, VERTEX_QUANTUM, vertexBlock } from '../../../src/isosurface/vertex-format.ts';
import { vertexFormatSnippet } from '../../../src/isosurface/wgsl.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { rng } from '../mc/reference.ts';

describe('vertex format', () => {
  /** Random edges (corner 0..4 per axis, axis, t) in random blocks, the extremes first (block 4095 on every axis, t 0 and 1). */
  function randomEdges(n: number, seed: number) {
    const random = rng(seed);
    const corners = new Uint32Array(4 * n);
    const blocks = new Uint32Array(4 * n);
    const ts = new Float32Array(n);
    for (let v = 0; v < n; v++) {
      for (let a = 0; a < 3; a++) {
        corners[4 * v + a] = v < 4 ? [0, 4, 2, 3][v] : Math.floor(random() * 5);
        blocks[4 * v + a] = v < 4 ? [0, 4095, 255, 256][v] : Math.floor(random() * 4096);
      }
      corners[4 * v + 3] = v % 3; // the axis
      ts[v] = v < 4 ? [0, 1, 0.5, 1 / 65535][v] : Math.fround(random());
    }
    return { corners, blocks, ts };
  }
  const at = (a: Uint32Array, v: number): [number, number, number] => [a[4 * v], a[4 * v + 1], a[4 * v + 2]];

  test('TS encode/decode: the edge, 16 bits along it, 12-bit block coordinates (16384 voxels per axis)', () => {
    const n = 1000;
    const { corners, blocks, ts } = randomEdges(n, 3);
    const packed = new Uint32Array(2 * n);
    for (let v = 0; v < n; v++) packed.set(encodeVertexEdge(at(corners, v), corners[4 * v + 3], ts[v], at(blocks, v)), 2 * v);
    expect(MAX_VERTEX_VOXELS).toBe(16384);
    // corner (4, 4, 4) on axis 1 at t = 1 in block (4095, 4095, 4095)
    expect(vertexBlock(packed[2], packed[3])).toEqual([4095, 4095, 4095]);
    const decoded = decodeVertices(packed, n, 2);
    for (let v = 0; v < n; v++) {
      for (let a = 0; a < 3; a++) {
        const expected = 4 * blocks[4 * v + a] + corners[4 * v + a] + (a === corners[4 * v + 3] ? ts[v] : 0);
        // half a step along the edge, and float32 rounding of coordinates up to 16384
        expect(Math.abs(decoded[3 * v + a] - expected)).toBeLessThanOrEqual(VERTEX_QUANTUM / 2 + Math.abs(expected) * 2 ** -23);
      }
    }
  });

  gpuTest('WGSL encode_vertex_edge / decode_vertex_position = the TS twin', async ({ gpu }) => {
    const { device } = gpu;
    const n = 4096;
    const { corners, blocks, ts } = randomEdges(n, 9);
    const pipeline = await createComputePipeline(
      device,
      'test.vertexFormat',
      [
        vertexFormatSnippet,
        {
          name: 'test/vertex_format.wgsl',
          code: /* wgsl */ `
@group(0) @binding(0) var<storage, read> corners: array<vec4u>;
@group(0) @binding(1) var<storage, read> blocks: array<vec4u>;
@group(0) @binding(2) var<storage, read> ts: array<f32>;
@group(0) @binding(3) var<storage, read_write> packed: array<vec2u>;
@group(0) @binding(4) var<storage, read_write> decoded: array<vec4f>;
@compute @workgroup_size(64) fn main(@builtin(global_invocation_id) id: vec3u) {
  let v = id.x;
  if (v >= arrayLength(&ts)) { return; }
  let w = encode_vertex_edge(corners[v].xyz, corners[v].w, ts[v], blocks[v].xyz);
  packed[v] = w;
  decoded[v] = vec4f(decode_vertex_position(w.x, w.y), 0.0);
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
    const buffers = [make(corners), make(blocks), make(ts), make(8 * n), make(16 * n)];
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
    const gpuPacked = await readU32(device, buffers[3]);
    const gpuDecoded = await readF32(device, buffers[4]);
    let different = 0;
    for (let v = 0; v < n; v++) {
      const [w0, w1] = encodeVertexEdge(at(corners, v), corners[4 * v + 3], ts[v], at(blocks, v));
      if (w0 !== gpuPacked[2 * v] || w1 !== gpuPacked[2 * v + 1]) different++;
    }
    expect(different).toBe(0);
    const tsDecoded = decodeVertices(gpuPacked, n, 2);
    for (let i = 0; i < 3 * n; i++) {
      const v = Math.floor(i / 3);
      expect(Math.abs(gpuDecoded[4 * v + (i % 3)] - tsDecoded[i])).toBeLessThanOrEqual(Math.abs(tsDecoded[i]) * 2 ** -22);
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
