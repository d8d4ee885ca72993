// `node benchmarks/run.mjs benchmarks/render-frames.ts [ROOT ...]`: GPU ms per frame of the
// renderer (src/render/surface-layer.ts) drawing an isosurface of a shared volume (FILE, ISOS,
// FRAMES, SIZE env) off screen, lit, the camera fitted to the volume: the median of FRAMES frames
// after a discarded first, timed by timestamp queries around the render pass (or queue wall time
// where the adapter has none). With several checkouts as arguments, each frame is drawn by every
// checkout in turn in one process on one device, so they share the machine's load (an A/B probe
// between builds, as benchmarks/isosurface-stages.ts).
import { readFileSync } from 'node:fs';
import { fileURLToPath } from 'node:url';

const here = fileURLToPath(new URL('..', import.meta.url));
const roots = process.argv.slice(2).length > 0 ? process.argv.slice(2) : [here];
const { requestNodeGpu } = await import(`${roots[0]}/src/gpu/node-gpu.ts`);
const gpu = await requestNodeGpu({ label: 'frames' });
const { device } = gpu;
const file = process.env.FILE ?? 'bonsai_256x256x256_float32.rate4.zfp';
const bytes = new Uint8Array(readFileSync(`${here}/../shared/data/volumes/${file}`));
const isos = (process.env.ISOS ?? '20.37,60.37').split(',').map(Number);
const frames = Number(process.env.FRAMES ?? 7);
const size = Number(process.env.SIZE ?? 1024);
const timed = device.features.has('timestamp-query');

interface Layer {
  setDrawData(d: unknown): void;
  draw(pass: GPURenderPassEncoder): void;
  destroy(): void;
}
interface Run {
  root: string;
  iso: { compute(t: number): Promise<{ triangles: number; vertices: number }>; drawData: unknown; destroy(): void };
  layer: Layer;
  group: GPUBindGroup;
}

const color = device.createTexture({ size: [size, size], format: 'rgba8unorm', usage: GPUTextureUsage.RENDER_ATTACHMENT });
const runs: Run[] = [];
let depthFormat: GPUTextureFormat = 'depth24plus';
for (const root of roots) {
  const { Isosurface } = await import(`${root}/src/isosurface/isosurface.ts`);
  const { loadZfpStream } = await import(`${root}/src/zfp/gpu-stream.ts`);
  const { SurfaceLayer } = await import(`${root}/src/render/surface-layer.ts`);
  const { ArcballCamera } = await import(`${root}/src/render/camera.ts`);
  const viewer = await import(`${root}/src/render/viewer.ts`);
  depthFormat = viewer.DEPTH_FORMAT;
  const stream = loadZfpStream(device, bytes, file);
  const iso = await Isosurface.create(gpu, stream, { initialCacheSlots: stream.info.blockCount >> 1, initialVertexCapacity: 2 ** 23 });
  const frameBindGroupLayout = viewer.createFrameBindGroupLayout(device);
  const camera = new ArcballCamera();
  camera.fit({ min: [0, 0, 0], max: stream.info.dims.map((n: number) => n - 1) });
  const layer: Layer = await SurfaceLayer.create({ device, format: 'rgba8unorm', frameBindGroupLayout, camera });
  const uniforms = device.createBuffer({ size: viewer.FRAME_UNIFORM_BYTES, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
  device.queue.writeBuffer(uniforms, 0, viewer.frameUniformData(camera, size, size));
  const group = device.createBindGroup({ layout: frameBindGroupLayout, entries: [{ binding: 0, resource: { buffer: uniforms } }] });
  runs.push({ root, iso, layer, group });
}
const depth = device.createTexture({ size: [size, size], format: depthFormat, usage: GPUTextureUsage.RENDER_ATTACHMENT });
const querySet = timed ? device.createQuerySet({ type: 'timestamp', count: 2 }) : undefined;
const resolve = device.createBuffer({ size: 16, usage: GPUBufferUsage.QUERY_RESOLVE | GPUBufferUsage.COPY_SRC });
const read = device.createBuffer({ size: 16, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });

async function frameMs(run: Run): Promise<number> {
  const encoder = device.createCommandEncoder();
  const pass = encoder.beginRenderPass({
    colorAttachments: [{ view: color.createView(), clearValue: { r: 0, g: 0, b: 0, a: 1 }, loadOp: 'clear', storeOp: 'store' }],
    depthStencilAttachment: { view: depth.createView(), depthClearValue: 1, depthLoadOp: 'clear', depthStoreOp: 'store' },
    ...(querySet ? { timestampWrites: { querySet, beginningOfPassWriteIndex: 0, endOfPassWriteIndex: 1 } } : {}),
  });
  pass.setBindGroup(0, run.group);
  run.layer.draw(pass);
  pass.end();
  if (querySet) {
    encoder.resolveQuerySet(querySet, 0, 2, resolve, 0);
    encoder.copyBufferToBuffer(resolve, 0, read, 0, 16);
  }
  const start = performance.now();
  device.queue.submit([encoder.finish()]);
  await device.queue.onSubmittedWorkDone();
  const wall = performance.now() - start;
  if (!querySet) return wall;
  await read.mapAsync(GPUMapMode.READ);
  const t = new BigUint64Array(read.getMappedRange().slice(0));
  read.unmap();
  return Number(t[1] - t[0]) / 1e6;
}

const median = (a: number[]) => [...a].sort((x, y) => x - y)[Math.floor(a.length / 2)];
console.log(
  `${file}, ${size}x${size}, median of ${frames} frames after a discarded first (${timed ? 'timestamp queries' : 'queue wall time'})`,
);
for (const t of isos) {
  const samples = runs.map(() => [] as number[]);
  const counts: string[] = [];
  for (const run of runs) {
    const s = await run.iso.compute(t);
    run.layer.setDrawData(run.iso.drawData);
    await frameMs(run); // discarded
    counts.push(`${s.triangles} triangles, ${s.vertices} vertices`);
  }
  for (let f = 0; f < frames; f++) for (let k = 0; k < runs.length; k++) samples[k].push(await frameMs(runs[k]));
  runs.forEach((run, k) => console.log(`iso ${t}: ${run.root}: ${median(samples[k]).toFixed(1)} ms per frame (${counts[k]})`));
}
for (const run of runs) {
  run.layer.destroy();
  run.iso.destroy();
}
device.destroy();
