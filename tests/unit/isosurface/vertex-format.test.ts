// The compressed vertex format: the WGSL encode/decode (vertex_format.wgsl,
// what the kernel writes and the renderer reads) against the TS twin
// (vertex-format.ts), up to the largest block coordinates of every block grid
// (12 bits per axis up to 4096 blocks, the bits each axis needs past that), and the layout
// constants shared by TS and WGSL.
import { readFileSync } from 'node:fs';
import { describe, expect, test } from 'vitest';
import { readF32, readU32 } from '../../../src/gpu/buffers.ts';
import { createComputePipeline } from '../../../src/gpu/pipeline-cache.ts';
import { A, C, NONE, S, SHARD_RECORD_BYTES, STATUS_CACHE_SHORTFALL, STATUS_VERTEX_OVERFLOW } from '../../../src/isosurface/layout.ts';
import { vertexBlockBits, surfaceDimsProblem } from '../../../src/core/limits.ts';
import {
  decodeVertices,
  encodeVertexEdge,
  MAX_VERTEX_VOXELS,
  VERTEX_BLOCK_BITS,
  VERTEX_QUANTUM,
  vertexBlock,
} from '../../../src/isosurface/vertex-format.ts';
import { vertexFormatSnippet } from '../../../src/isosurface/wgsl.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { rng } from '../mc/reference.ts';

describe('vertex format', () => {
  // Block grids (blocks of 4^3 per axis) and the bits their axes take: 12 each up to 4096 blocks per axis (16384
  // voxels), otherwise what each axis needs, 36 bits in all (src/core/limits.ts).
  const grids: { grid: [number, number, number]; bits: [number, number] }[] = [
    { grid: [4096, 4096, 4096], bits: [12, 12] },
    { grid: [17, 3, 1], bits: [12, 12] },
    { grid: [8192, 16, 16], bits: [13, 4] }, // 32768 x 64 x 64 voxels
    { grid: [1, 1, 6683], bits: [0, 0] }, // 1 x 1 x 26730
    { grid: [7500, 5000, 25], bits: [13, 13] }, // 30000 x 20000 x 100
    { grid: [2 ** 18, 2 ** 18, 1], bits: [18, 18] }, // all 36 bits in x and y
    { grid: [3, 2 ** 22, 9], bits: [2, 22] }, // 2^24 voxels along y, the most an axis may have
  ];
  const dimsOf = (grid: readonly number[]) => grid.map((n) => 4 * n);

  /** Random edges (corner 0..4 per axis, axis, t) in random blocks of random grids, the extremes first (the grid's last block, t 0 and 1). */
  function randomEdges(n: number, seed: number) {
    const random = rng(seed);
    const corners = new Uint32Array(4 * n);
    const blocks = new Uint32Array(4 * n);
    const gridOf = new Uint32Array(4 * n);
    const ts = new Float32Array(n);
    for (let v = 0; v < n; v++) {
      const { grid } = grids[v % grids.length];
      const extreme = v < 4 * grids.length ? Math.floor(v / grids.length) : -1;
      for (let a = 0; a < 3; a++) {
        corners[4 * v + a] = extreme >= 0 ? [0, 4, 2, 3][extreme] : Math.floor(random() * 5);
        blocks[4 * v + a] =
          extreme >= 0 ? [0, grid[a] - 1, grid[a] >> 1, Math.min(256, grid[a] - 1)][extreme] : Math.floor(random() * grid[a]);
        gridOf[4 * v + a] = grid[a];
      }
      corners[4 * v + 3] = v % 3; // the axis
      ts[v] = extreme >= 0 ? [0, 1, 0.5, 1 / 65535][extreme] : Math.fround(random());
    }
    return { corners, blocks, gridOf, ts };
  }
  const at = (a: Uint32Array, v: number): [number, number, number] => [a[4 * v], a[4 * v + 1], a[4 * v + 2]];

  test('the block field: 12 bits per axis up to 4096 blocks, past that the bits each axis needs, 36 in all; larger volumes refused by name', () => {
    for (const { grid, bits } of grids) expect(vertexBlockBits(grid), grid.join('x')).toEqual(bits);
    expect(MAX_VERTEX_VOXELS).toBe(16384);
    expect(VERTEX_BLOCK_BITS).toBe(36);
    expect(surfaceDimsProblem([32768, 64, 64])).toBeNull();
    expect(surfaceDimsProblem([30000, 20000, 100])).toBeNull();
    expect(surfaceDimsProblem([12, 2 ** 24, 36])).toBeNull();
    expect(surfaceDimsProblem([12, 2 ** 24 + 1, 36])).toMatch(
      /16777217 along an axis.* float32, whole voxels exact up to 16777216 per axis$/,
    );
    expect(surfaceDimsProblem([2 ** 20, 2 ** 20, 64])).toMatch(
      /^1048576x1048576x64 voxels: its 262144 x 262144 x 16 blocks of 4\^3 need 18 \+ 18 \+ 4 = 40 bits .* in 36 bits$/,
    );
    // the layout of volumes up to 16384 voxels per axis did not change: dims or none, the same words
    expect(encodeVertexEdge([4, 4, 4], 1, 1, [4095, 4095, 4095], [16384, 16384, 16384])).toEqual(
      encodeVertexEdge([4, 4, 4], 1, 1, [4095, 4095, 4095]),
    );
    expect(vertexBlock(...encodeVertexEdge([4, 4, 4], 1, 1, [4095, 4095, 4095]))).toEqual([4095, 4095, 4095]);
  });

  test('TS encode/decode: the edge, 16 bits along it, the block on every grid', () => {
    const n = 7000;
    const { corners, blocks, gridOf, ts } = randomEdges(n, 3);
    for (let v = 0; v < n; v++) {
      const dims = dimsOf(at(gridOf, v));
      const packed = new Uint32Array(encodeVertexEdge(at(corners, v), corners[4 * v + 3], ts[v], at(blocks, v), dims));
      expect(vertexBlock(packed[0], packed[1], dims)).toEqual(at(blocks, v));
      const decoded = decodeVertices(packed, 1, 2, dims);
      for (let a = 0; a < 3; a++) {
        const expected = 4 * blocks[4 * v + a] + corners[4 * v + a] + (a === corners[4 * v + 3] ? ts[v] : 0);
        // half a step along the edge, and float32 rounding of the coordinates
        expect(Math.abs(decoded[a] - expected)).toBeLessThanOrEqual(VERTEX_QUANTUM / 2 + Math.abs(expected) * 2 ** -23);
      }
    }
  });

  gpuTest('WGSL encode_vertex_edge / decode_vertex_position = the TS twin, on every grid', async ({ gpu }) => {
    const { device } = gpu;
    const n = 64 * 128;
    const { corners, blocks, gridOf, ts } = randomEdges(n, 9);
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
@group(0) @binding(5) var<storage, read> grids: array<vec4u>;
@compute @workgroup_size(64) fn main(@builtin(global_invocation_id) id: vec3u) {
  let v = id.x;
  if (v >= arrayLength(&ts)) { return; }
  let w = encode_vertex_edge(corners[v].xyz, corners[v].w, ts[v], blocks[v].xyz, grids[v].xyz);
  packed[v] = w;
  decoded[v] = vec4f(decode_vertex_position(w.x, w.y, grids[v].xyz), 0.0);
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
    const buffers = [make(corners), make(blocks), make(ts), make(8 * n), make(16 * n), make(gridOf)];
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
      const dims = dimsOf(at(gridOf, v));
      const [w0, w1] = encodeVertexEdge(at(corners, v), corners[4 * v + 3], ts[v], at(blocks, v), dims);
      if (w0 !== gpuPacked[2 * v] || w1 !== gpuPacked[2 * v + 1]) different++;
      const tsDecoded = decodeVertices(gpuPacked.subarray(2 * v, 2 * v + 2), 1, 2, dims);
      for (let a = 0; a < 3; a++)
        expect(Math.abs(gpuDecoded[4 * v + a] - tsDecoded[a])).toBeLessThanOrEqual(Math.abs(tsDecoded[a]) * 2 ** -22);
    }
    expect(different).toBe(0);
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
