// `npm run bench:surfaces` (node benchmarks/run.mjs benchmarks/surface-set.ts):
// several surfaces of one volume as the page draws them (src/app/surfaces/):
// one pipeline, the selected surface live, the others GPU copies, each its own
// SurfaceLayer; see-through ones depth peeled (src/render/depth-peel.ts).
// Per configuration (1 opaque surface; 2 and 4 surfaces with the first at
// opacity 0.35), off screen at SIZE x SIZE, the camera fitted:
//   - frame ms: the whole frame (opaque pass, the peels the scene needs and their composites) between
//     GPU timestamps (queue wall time without timestamp-query), median of
//     FRAMES after a discarded first;
//   - new surface ms: moving the live surface by small steps (the others stay
//     copies: nothing else is recomputed), the pipeline's GPU ms per surface,
//     median after a discarded first;
//   - GPU bytes of the copies.
// FILE (default bonsai rate 4), ISOS (4 values), SIZE, FRAMES from the
// environment; JSON to benchmarks/results/surface-set-<swiftshader or the GPU>.json.
import { readFileSync } from 'node:fs';
import { fileURLToPath } from 'node:url';
import { describeAdapter } from '../src/gpu/device.ts';
import { requestNodeGpu } from '../src/gpu/node-gpu.ts';
import { Isosurface } from '../src/isosurface/isosurface.ts';
import type { SurfaceSnapshot } from '../src/isosurface/snapshot.ts';
import { ArcballCamera } from '../src/render/camera.ts';
import { DepthPeeler } from '../src/render/depth-peel.ts';
import { SurfaceLayer } from '../src/render/surface-layer.ts';
import { createFrameBindGroupLayout, DEPTH_FORMAT, FRAME_UNIFORM_BYTES, frameUniformData } from '../src/render/viewer.ts';
import { loadZfpStream } from '../src/zfp/gpu-stream.ts';
import { printTable, summarize, writeJson } from './lib/report.ts';

const here = fileURLToPath(new URL('..', import.meta.url));
const file = process.env.FILE ?? 'bonsai_256x256x256_float32.rate4.zfp';
const isos = (process.env.ISOS ?? '40.37,80.37,120.37,160.37').split(',').map(Number);
const size = Number(process.env.SIZE ?? 768);
const frames = Number(process.env.FRAMES ?? 7);
const steps = Number(process.env.STEPS ?? 7);

const gpu = await requestNodeGpu({ label: 'surface-set' });
const { device } = gpu;
const timed = device.features.has('timestamp-query');
const stream = loadZfpStream(device, new Uint8Array(readFileSync(`${here}/../shared/data/volumes/${file}`)), file);
const iso = await Isosurface.create(gpu, stream, { memoryBudgetBytes: 1536 * 2 ** 20 });
const format: GPUTextureFormat = 'rgba8unorm';
const frameLayout = createFrameBindGroupLayout(device);
const camera = new ArcballCamera();
camera.fit({ min: [0, 0, 0], max: stream.info.dims.map((n) => n - 1) as [number, number, number] });
const uniforms = device.createBuffer({ size: FRAME_UNIFORM_BYTES, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
device.queue.writeBuffer(uniforms, 0, frameUniformData(camera, size, size) as Float32Array<ArrayBuffer>);
const frameBindGroup = device.createBindGroup({ layout: frameLayout, entries: [{ binding: 0, resource: { buffer: uniforms } }] });
const colour = device.createTexture({ size: [size, size], format, usage: GPUTextureUsage.RENDER_ATTACHMENT });
const depth = device.createTexture({
  size: [size, size],
  format: DEPTH_FORMAT,
  usage: GPUTextureUsage.RENDER_ATTACHMENT | GPUTextureUsage.TEXTURE_BINDING,
});
const target = colour.createView();
const depthView = depth.createView();
const peeler = await DepthPeeler.create(device, format);
peeler.adaptive = true; // as the page peels: one layer past the deepest that drew, up to 8
const querySet = timed ? device.createQuerySet({ type: 'timestamp', count: 2 }) : undefined;
const resolve = device.createBuffer({ size: 16, usage: GPUBufferUsage.QUERY_RESOLVE | GPUBufferUsage.COPY_SRC });
const read = device.createBuffer({ size: 16, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });

async function frameMs(layers: SurfaceLayer[]): Promise<number> {
  const encoder = device.createCommandEncoder();
  peeler.lastLayers = 0;
  const pass = encoder.beginRenderPass({
    colorAttachments: [{ view: target, clearValue: { r: 0, g: 0, b: 0, a: 1 }, loadOp: 'clear', storeOp: 'store' }],
    depthStencilAttachment: { view: depthView, depthClearValue: 1, depthLoadOp: 'clear', depthStoreOp: 'store' },
    ...(querySet ? { timestampWrites: { querySet, beginningOfPassWriteIndex: 0 } } : {}),
  });
  pass.setBindGroup(0, frameBindGroup);
  for (const l of layers) l.draw(pass);
  pass.end();
  if (DepthPeeler.anyTransparent(layers))
    peeler.encode(encoder, { target, opaqueDepth: depthView, width: size, height: size, frameBindGroup, layers });
  // the end of the frame: an empty pass after the last composite
  encoder.beginComputePass(querySet ? { timestampWrites: { querySet, endOfPassWriteIndex: 1 } } : {}).end();
  if (querySet) {
    encoder.resolveQuerySet(querySet, 0, 2, resolve, 0);
    encoder.copyBufferToBuffer(resolve, 0, read, 0, 16);
  }
  const start = performance.now();
  device.queue.submit([encoder.finish()]);
  await device.queue.onSubmittedWorkDone();
  const wall = performance.now() - start;
  await new Promise((r) => setTimeout(r, 0)); // the peel counts are read back
  if (!querySet) return wall;
  await read.mapAsync(GPUMapMode.READ);
  const t = new BigUint64Array(read.getMappedRange().slice(0));
  read.unmap();
  return Number(t[1] - t[0]) / 1e6;
}

interface Row {
  surfaces: number;
  seeThrough: number;
  triangles: number;
  copyBytes: number;
  frameMs: number;
  /** Layers the last frame peeled (0: nothing see-through). */
  peels: number;
  newSurfaceMs: number;
}
const rows: Row[] = [];
const configs = [
  { n: 1, seeThrough: 0 },
  { n: 2, seeThrough: 1 },
  { n: 4, seeThrough: 1 },
];
for (const { n, seeThrough } of configs) {
  const values = isos.slice(0, n);
  const copies: SurfaceSnapshot[] = [];
  const layers: SurfaceLayer[] = [];
  let triangles = 0;
  // the others first, each copied; the last stays live
  for (let i = 0; i < n; i++) {
    const s = await iso.compute(values[i]);
    triangles += s.triangles;
    const layer = await SurfaceLayer.create({ device, format, frameBindGroupLayout: frameLayout, camera });
    layer.style.opacity = i < seeThrough ? 0.35 : 1;
    if (i < n - 1) {
      const copy = iso.newCopy();
      iso.copyInto(copy);
      copies.push(copy);
      layer.setDrawData(copy.drawData);
    } else layer.setDrawData(iso.drawData);
    layers.push(layer);
  }
  const frame = summarize(
    await (async () => {
      const all: number[] = [];
      for (let f = 0; f <= frames; f++) all.push(await frameMs(layers));
      return all;
    })(),
  );
  // moving the live surface: small steps around its isovalue (cache warm)
  const live = values[n - 1];
  const perSurface: number[] = [];
  for (let k = 0; k <= steps; k++) perSurface.push((await iso.compute(live + (k % 2 === 0 ? 1 : -1) * (1 + k) * 0.25)).gpuMs);
  rows.push({
    surfaces: n,
    seeThrough,
    triangles,
    copyBytes: copies.reduce((a, c) => a + c.byteSize, 0),
    frameMs: frame.median,
    peels: peeler.lastLayers,
    newSurfaceMs: summarize(perSurface).median,
  });
  for (const l of layers) l.destroy();
  for (const c of copies) c.destroy();
}

const adapter = describeAdapter(gpu.adapter);
printTable(
  `${file}, ${size}x${size}, isovalues ${values(isos)}: median of ${frames} frames and ${steps} surfaces after a discarded first (${timed ? 'GPU timestamps' : 'queue wall time'}), ${adapter}`,
  ['surfaces', 'see-through', 'triangles', 'copies MiB', 'frame ms', 'peels', 'new surface ms'],
  rows.map((r) => [r.surfaces, r.seeThrough, r.triangles, r.copyBytes / 2 ** 20, r.frameMs, r.peels, r.newSurfaceMs]),
);
writeJson(
  `${here}/benchmarks/results/surface-set-${/swiftshader/i.test(adapter) ? 'swiftshader' : adapter.split(' / ')[0].replace(/\W+/g, '-').toLowerCase()}.json`,
  {
    file,
    size,
    frames,
    steps,
    isovalues: isos,
    adapter,
    timing: timed ? 'timestamp-query' : 'queue wall time',
    peelLayers: peeler.layers,
    rows,
  },
);
peeler.destroy();
iso.destroy();
stream.destroy();
device.destroy();

function values(v: number[]): string {
  return v.join(', ');
}
