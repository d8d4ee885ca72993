// The path from a new isovalue to the draw call neither reads back nor
// waits: with GPUBuffer.mapAsync and GPUQueue.onSubmittedWorkDone counted,
// setIsovalue() followed at once by a real draw submission (a render pass
// that decodes the compressed vertices with vertex_format.wgsl and draws each
// shard with drawIndirect) makes zero calls to either, and exactly one
// submission for the computation. The draw arguments are the GPU's: the
// buffer cannot be written by the host (no COPY_DST) and a later readback
// holds the new surface's vertex count.
import { describe, expect } from 'vitest';
import { Isosurface } from '../../../src/isosurface/isosurface.ts';
import type { IsosurfaceDrawData, IsosurfaceStats } from '../../../src/isosurface/types.ts';
import { vertexFormatSnippet } from '../../../src/isosurface/wgsl.ts';
import { readU32 } from '../../../src/gpu/buffers.ts';
import { createShaderModule } from '../../../src/gpu/wgsl.ts';
import type { Dims } from '../../../src/core/naming.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { compressVolume, makeField } from './helpers.ts';

const SIZE = 64;

/** A minimal renderer: orthographic x/y, white triangles on black. */
async function createDrawer(device: GPUDevice, info: IsosurfaceDrawData['info']) {
  const module = await createShaderModule(device, 'test.draw', [
    vertexFormatSnippet,
    {
      name: 'test/draw.wgsl',
      code: /* wgsl */ `
struct View { grid: vec3u, _pad: u32, extent: vec3f, _pad2: f32 }
@group(0) @binding(0) var<uniform> view: View;
@vertex fn vs(@location(0) v: vec2u) -> @builtin(position) vec4f {
  let p = decode_vertex_position(v.x, v.y, view.grid) / view.extent;
  return vec4f(p.xy * 2.0 - 1.0, 0.5, 1.0);
}
@fragment fn fs() -> @location(0) vec4f { return vec4f(1.0); }`,
    },
  ]);
  const pipeline = await device.createRenderPipelineAsync({
    layout: 'auto',
    vertex: {
      module,
      entryPoint: 'vs',
      buffers: [{ arrayStride: 12, attributes: [{ shaderLocation: 0, offset: 0, format: 'uint32x2' }] }],
    },
    fragment: { module, entryPoint: 'fs', targets: [{ format: 'rgba8unorm' }] },
    primitive: { topology: 'triangle-list' },
  });
  const view = device.createBuffer({ size: 32, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
  device.queue.writeBuffer(view, 0, new Uint32Array([...info.blockGrid, 0]));
  device.queue.writeBuffer(view, 16, new Float32Array(info.dims.map((n) => n - 1)));
  const target = device.createTexture({
    size: [SIZE, SIZE],
    format: 'rgba8unorm',
    usage: GPUTextureUsage.RENDER_ATTACHMENT | GPUTextureUsage.COPY_SRC,
  });
  const group = device.createBindGroup({ layout: pipeline.getBindGroupLayout(0), entries: [{ binding: 0, resource: { buffer: view } }] });
  return {
    encodeDraw(encoder: GPUCommandEncoder, data: IsosurfaceDrawData) {
      const pass = encoder.beginRenderPass({
        colorAttachments: [{ view: target.createView(), loadOp: 'clear', storeOp: 'store', clearValue: [0, 0, 0, 1] }],
      });
      pass.setPipeline(pipeline);
      pass.setBindGroup(0, group);
      pass.setVertexBuffer(0, data.vertices);
      for (const s of data.shards) {
        pass.setIndexBuffer(s.indices, 'uint32');
        pass.drawIndexedIndirect(s.drawArgs, s.drawArgsOffset);
      }
      pass.end();
    },
    async litPixels(): Promise<number> {
      const out = device.createBuffer({ size: SIZE * SIZE * 4, usage: GPUBufferUsage.COPY_DST | GPUBufferUsage.COPY_SRC });
      const encoder = device.createCommandEncoder();
      encoder.copyTextureToBuffer({ texture: target }, { buffer: out, bytesPerRow: SIZE * 4 }, [SIZE, SIZE]);
      device.queue.submit([encoder.finish()]);
      const px = await readU32(device, out);
      out.destroy();
      return px.filter((p) => (p & 0xff) !== 0).length;
    },
  };
}

describe('no readback on the way to the draw', () => {
  gpuTest('setIsovalue -> draw submission: zero mapAsync, zero onSubmittedWorkDone, GPU-written draw arguments', async ({ gpu }) => {
    const { device } = gpu;
    const dims: Dims = [40, 36, 28];
    const stream = await compressVolume(device, makeField(dims, 77, 'blobs'), dims, 8);
    // several shards, so several indirect draws
    const iso = await Isosurface.create(gpu, stream, { maxVertexBindingBytes: 4 * 3000 });
    const [lo, hi] = iso.info.valueRange;
    // the second surface is inside the first (blobs): no growth needed
    const first = Math.fround(lo + 0.25 * (hi - lo));
    const second = Math.fround(lo + 0.5 * (hi - lo));
    const before = await iso.compute(first); // warm: pipelines used once, buffers grown
    const drawer = await createDrawer(device, iso.info);

    const bufferProto = Object.getPrototypeOf(iso.drawData.vertices) as GPUBuffer;
    const queueProto = Object.getPrototypeOf(device.queue) as GPUQueue;
    const originals = { mapAsync: bufferProto.mapAsync, done: queueProto.onSubmittedWorkDone, submit: queueProto.submit };
    const calls = { mapAsync: 0, onSubmittedWorkDone: 0, submit: 0 };
    bufferProto.mapAsync = function (this: GPUBuffer, ...a: Parameters<GPUBuffer['mapAsync']>) {
      calls.mapAsync++;
      return originals.mapAsync.apply(this, a);
    };
    queueProto.onSubmittedWorkDone = function (this: GPUQueue) {
      calls.onSubmittedWorkDone++;
      return originals.done.apply(this);
    };
    queueProto.submit = function (this: GPUQueue, buffers: Iterable<GPUCommandBuffer>) {
      calls.submit++;
      return originals.submit.call(this, buffers);
    };
    let atDraw: typeof calls;
    let statsPromise: Promise<IsosurfaceStats>;
    try {
      statsPromise = new Promise((resolve) => {
        const off = iso.onStats((s) => {
          off();
          resolve(s);
        });
      });
      iso.setIsovalue(second);
      const afterSet = { ...calls };
      const encoder = device.createCommandEncoder({ label: 'test.draw' });
      drawer.encodeDraw(encoder, iso.drawData);
      device.queue.submit([encoder.finish()]);
      atDraw = { ...calls };
      expect(afterSet.submit).toBe(1); // the whole computation: one submission
    } finally {
      bufferProto.mapAsync = originals.mapAsync;
      queueProto.onSubmittedWorkDone = originals.done;
      queueProto.submit = originals.submit;
    }
    expect(atDraw.mapAsync).toBe(0);
    expect(atDraw.onSubmittedWorkDone).toBe(0);
    expect(atDraw.submit).toBe(2);

    const stats = await statsPromise;
    expect(stats.isovalue).toBe(second);
    expect(stats.grew).toBe(false); // the surface above was drawn from this very submission
    expect(stats.indices).not.toBe(before.indices);
    const data = iso.drawData;
    expect(data.shards.length).toBeGreaterThan(1);
    let drawn = 0;
    for (const s of data.shards) {
      expect(s.drawArgs.usage & GPUBufferUsage.COPY_DST).toBe(0);
      const args = await readU32(device, s.drawArgs, s.drawArgsOffset, 4);
      expect(args[1]).toBe(1);
      drawn += args[0];
    }
    expect(drawn).toBe(stats.indices);
    expect(await drawer.litPixels()).toBeGreaterThan(50);
    iso.destroy();
    stream.destroy();
  });
});
