// The WGSL helpers (shaders/mc/case_table.wgsl) with the packed table on the test
// device: every case, random corner values and cells, against the TS table and the
// documented float32 vertex formula.
import { expect } from 'vitest';
import { readF32, readU32 } from '../../../src/gpu/buffers.ts';
import { createComputePipeline } from '../../../src/gpu/pipeline-cache.ts';
import { CASE_TRIANGLE_EDGES, CASE_VERTEX_COUNT, EDGE_CORNERS } from '../../../src/mc/case-table.ts';
import { createCaseTableBuffer, mcCaseTableSnippet } from '../../../src/mc/case-table-wgsl.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { rng } from './reference.ts';

const kernel = {
  name: 'test/mc-case-table.wgsl',
  code: /* wgsl */ `
struct Params { iso: f32, count: u32 }
@group(0) @binding(0) var<storage, read> table: array<u32>;
@group(0) @binding(1) var<storage, read> corners: array<f32>;
@group(0) @binding(2) var<storage, read> cells: array<u32>;
@group(0) @binding(3) var<storage, read_write> info: array<u32>;
@group(0) @binding(4) var<storage, read_write> pos: array<f32>;
@group(0) @binding(5) var<uniform> params: Params;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u) {
  let s = gid.x;
  if (s >= params.count) { return; }
  var v: array<f32, 8>;
  for (var q = 0u; q < 8u; q++) { v[q] = corners[8u * s + q]; }
  let c = mc_case_index(v, params.iso);
  let words = vec2u(table[2u * c], table[2u * c + 1u]);
  let n = 3u * mc_case_triangles(words);
  info[17u * s] = c;
  info[17u * s + 1u] = n;
  let cell = vec3u(cells[3u * s], cells[3u * s + 1u], cells[3u * s + 2u]);
  for (var j = 0u; j < n; j++) {
    let e = mc_case_edge(words, j);
    info[17u * s + 2u + j] = e;
    let p = mc_edge_vertex(cell, e, v[mc_edge_lower(e)], v[mc_edge_upper(e)], params.iso);
    pos[45u * s + 3u * j] = p.x;
    pos[45u * s + 3u * j + 1u] = p.y;
    pos[45u * s + 3u * j + 2u] = p.z;
  }
}`,
};

gpuTest('WGSL helpers decode the packed table and place vertices by the shared formula', async ({ gpu }) => {
  const { device } = gpu;
  const f = Math.fround;
  const iso = f(37.37);
  const perCase = 4;
  const count = 256 * perCase;
  const r = rng(11);
  const corners = new Float32Array(8 * count);
  const cells = new Uint32Array(3 * count);
  for (let s = 0; s < count; s++) {
    const c = s % 256;
    for (let q = 0; q < 8; q++) {
      const inside = (c >> q) & 1;
      // Some inside corners sit exactly on iso: value >= iso is inside.
      corners[8 * s + q] = inside ? (r() < 0.1 ? iso : iso + 0.001 + r() * 50) : iso - 0.001 - r() * 50;
    }
    for (let a = 0; a < 3; a++) cells[3 * s + a] = Math.floor(r() * 3000);
  }
  const usage = GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST;
  const make = (label: string, data: Float32Array<ArrayBuffer> | Uint32Array<ArrayBuffer>, extra = 0) => {
    const b = device.createBuffer({ label, size: data.byteLength, usage: usage | extra });
    device.queue.writeBuffer(b, 0, data);
    return b;
  };
  const table = createCaseTableBuffer(device);
  const cornerBuf = make('test.corners', corners);
  const cellBuf = make('test.cells', cells);
  const info = make('test.info', new Uint32Array(17 * count), GPUBufferUsage.COPY_SRC);
  const pos = make('test.pos', new Float32Array(45 * count), GPUBufferUsage.COPY_SRC);
  const params = device.createBuffer({ label: 'test.params', size: 8, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
  device.queue.writeBuffer(params, 0, new Uint32Array([new Uint32Array(new Float32Array([iso]).buffer)[0], count]));
  const pipeline = await createComputePipeline(device, 'test.mcCaseTable', [mcCaseTableSnippet, kernel], 'main');
  const bind = device.createBindGroup({
    layout: pipeline.getBindGroupLayout(0),
    entries: [table, cornerBuf, cellBuf, info, pos, params].map((buffer, binding) => ({ binding, resource: { buffer } })),
  });
  const encoder = device.createCommandEncoder();
  const pass = encoder.beginComputePass();
  pass.setPipeline(pipeline);
  pass.setBindGroup(0, bind);
  pass.dispatchWorkgroups(count / 64);
  pass.end();
  device.queue.submit([encoder.finish()]);
  const gotInfo = await readU32(device, info);
  const gotPos = await readF32(device, pos);

  let exact = 0;
  let total = 0;
  let worst = 0;
  for (let s = 0; s < count; s++) {
    const c = s % 256;
    const n = CASE_VERTEX_COUNT[c];
    expect([s, gotInfo[17 * s], gotInfo[17 * s + 1]]).toEqual([s, c, n]);
    expect(Array.from(gotInfo.subarray(17 * s + 2, 17 * s + 2 + n))).toEqual(CASE_TRIANGLE_EDGES[c]);
    for (let j = 0; j < n; j++) {
      const e = CASE_TRIANGLE_EDGES[c][j];
      const lo = EDGE_CORNERS[2 * e];
      const v0 = corners[8 * s + lo];
      const t = f(f(iso - v0) / f(corners[8 * s + EDGE_CORNERS[2 * e + 1]] - v0));
      for (let a = 0; a < 3; a++) {
        const base = cells[3 * s + a] + ((lo >> a) & 1);
        const want = a === e >> 2 ? f(base + t) : base;
        const got = gotPos[45 * s + 3 * j + a];
        total++;
        if (got === want) exact++;
        // WGSL's f32 division is within 2.5 ULP: allow a few ULP of the coordinate.
        const ulp = 2 ** (Math.floor(Math.log2(Math.max(Math.abs(want), 2 ** -126))) - 23);
        worst = Math.max(worst, Math.abs(got - want) / ulp);
      }
    }
  }
  // SwiftShader gives exact results (0 ULP); a GPU may round the division differently.
  expect(worst, `${exact}/${total} coordinates bit-identical`).toBeLessThanOrEqual(3);
  for (const b of [table, cornerBuf, cellBuf, info, pos, params]) b.destroy();
});
