// One frame of a layer into an offscreen target, read back: what `render`,
// the benchmarks and the tests draw headless, and what the page's rays read
// their own depth with (src/app/ray-guidance.ts).
import type { ArcballCamera } from './camera.ts';
import { DEPTH_FORMAT, FRAME_UNIFORM_BYTES, frameUniformData, type RenderLayer } from './viewer.ts';

const BACKGROUND = { r: 0.09, g: 0.1, b: 0.12, a: 1 };

/**
 * One frame of `layer` into an offscreen target: colour (RGBA8, or the
 * layer's pipelines' `format`: bytes as that format has them), depth, and
 * its time (GPU timestamps where the adapter has them, else the wall time to
 * the read back). `colour: false`: the depth alone read back (colour empty).
 * `pixels: false` (a benchmark's frame): nothing read back,
 * colour and depth empty, the wall time to the queue's done.
 */
export async function renderOffscreen(
  device: GPUDevice,
  frameLayout: GPUBindGroupLayout,
  camera: ArcballCamera,
  width: number,
  height: number,
  layer: RenderLayer,
  {
    pixels = true,
    colour: readsColour = true,
    format = 'rgba8unorm',
  }: { pixels?: boolean; colour?: boolean; format?: GPUTextureFormat } = {},
): Promise<{ colour: Uint8Array; depth: Float32Array; ms: number; timing: 'timestamp-query' | 'wall' }> {
  const colour = device.createTexture({
    size: [width, height],
    format,
    usage: GPUTextureUsage.RENDER_ATTACHMENT | GPUTextureUsage.COPY_SRC,
  });
  const depth = device.createTexture({
    size: [width, height],
    format: DEPTH_FORMAT,
    usage: GPUTextureUsage.RENDER_ATTACHMENT | GPUTextureUsage.COPY_SRC,
  });
  const uniforms = device.createBuffer({ size: FRAME_UNIFORM_BYTES, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
  device.queue.writeBuffer(uniforms, 0, frameUniformData(camera, width, height) as Float32Array<ArrayBuffer>);
  const group = device.createBindGroup({ layout: frameLayout, entries: [{ binding: 0, resource: { buffer: uniforms } }] });
  const colourRow = 256 * Math.ceil((4 * width) / 256);
  const readBytes = pixels ? colourRow * height : 4;
  const readColour = device.createBuffer({ size: readsColour ? readBytes : 4, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
  const readDepth = device.createBuffer({ size: readBytes, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
  const timed = device.features.has('timestamp-query');
  const querySet = timed ? device.createQuerySet({ type: 'timestamp', count: 2 }) : undefined;
  const resolve = timed ? device.createBuffer({ size: 16, usage: GPUBufferUsage.QUERY_RESOLVE | GPUBufferUsage.COPY_SRC }) : undefined;
  const readTimes = timed ? device.createBuffer({ size: 16, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST }) : undefined;
  const encoder = device.createCommandEncoder({ label: 'render' });
  const pass = encoder.beginRenderPass({
    colorAttachments: [{ view: colour.createView(), clearValue: BACKGROUND, loadOp: 'clear', storeOp: 'store' }],
    depthStencilAttachment: { view: depth.createView(), depthClearValue: 1, depthLoadOp: 'clear', depthStoreOp: 'store' },
    ...(querySet ? { timestampWrites: { querySet, beginningOfPassWriteIndex: 0, endOfPassWriteIndex: 1 } } : {}),
  });
  pass.setBindGroup(0, group);
  layer.draw(pass);
  pass.end();
  if (pixels) {
    if (readsColour) encoder.copyTextureToBuffer({ texture: colour }, { buffer: readColour, bytesPerRow: colourRow }, [width, height]);
    encoder.copyTextureToBuffer({ texture: depth, aspect: 'depth-only' }, { buffer: readDepth, bytesPerRow: colourRow }, [width, height]);
  }
  if (querySet && resolve && readTimes) {
    encoder.resolveQuerySet(querySet, 0, 2, resolve, 0);
    encoder.copyBufferToBuffer(resolve, 0, readTimes, 0, 16);
  }
  const started = performance.now();
  device.queue.submit([encoder.finish()]);
  await Promise.all(
    pixels
      ? [
          readsColour ? readColour.mapAsync(GPUMapMode.READ) : undefined,
          readDepth.mapAsync(GPUMapMode.READ),
          readTimes?.mapAsync(GPUMapMode.READ),
        ]
      : [device.queue.onSubmittedWorkDone(), readTimes?.mapAsync(GPUMapMode.READ)],
  );
  let ms = performance.now() - started;
  if (readTimes) {
    const t = new BigUint64Array(readTimes.getMappedRange());
    if (t[1] > t[0]) ms = Number(t[1] - t[0]) / 1e6;
    readTimes.unmap();
  }
  if (!pixels) {
    for (const x of [colour, depth, uniforms, readColour, readDepth, resolve, readTimes]) x?.destroy();
    querySet?.destroy();
    return { colour: new Uint8Array(0), depth: new Float32Array(0), ms, timing: readTimes ? 'timestamp-query' : 'wall' };
  }
  const d = new Float32Array(readDepth.getMappedRange());
  const out = { colour: new Uint8Array(readsColour ? 4 * width * height : 0), depth: new Float32Array(width * height) };
  for (let y = 0; y < height; y++) out.depth.set(d.subarray((y * colourRow) / 4, (y * colourRow) / 4 + width), width * y);
  readDepth.unmap();
  if (readsColour) {
    const c = new Uint8Array(readColour.getMappedRange());
    for (let y = 0; y < height; y++) out.colour.set(c.subarray(y * colourRow, y * colourRow + 4 * width), 4 * width * y);
    readColour.unmap();
  }
  for (const x of [colour, depth, uniforms, readColour, readDepth, resolve, readTimes]) x?.destroy();
  querySet?.destroy();
  return { colour: out.colour, depth: out.depth, ms, timing: readTimes ? 'timestamp-query' : 'wall' };
}
