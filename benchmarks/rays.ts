// `npm run bench:rays` (node benchmarks/run.mjs benchmarks/rays.ts): the
// surface drawn as triangles (SurfaceLayer) and ray cast in the block cache
// (RayLayer, issue 46), side by side, volumes opened whole, at SIZE (default
// 1280x720), the camera fitted and then orbited:
//   - surface ms: the pipeline's computation of a new isovalue (GPU ms;
//     the rays read the cache it leaves; today it makes the triangles too);
//   - first image ms: that computation plus the first frame (GPU), per mode;
//   - frame ms: median of FRAMES orbit frames after a discarded first (GPU
//     timestamps, else queue wall time), per mode;
//   - the surface's GPU bytes: cache (what the rays need) and vertices and
//     indices (what only the triangles need).
// FILES (comma list of shared volumes), ISOS (one per file), SIZE, FRAMES from
// the environment; JSON to benchmarks/results/rays-<adapter>.json.
// With STORE (a Zarr store, e.g. a converted gen:2048x2048x2048), also the
// store refined by the view within STORE_BUDGET MB (default 256) at
// STORE_ISO, Fit and framed on STORE_BOX (x0,y0,z0,x1,y1,z1, level-0
// voxels), each mode planning its own cut (rays: surfaces of block caches
// only, so the budget holds bricks, not vertices; then refined where the
// image's rays found the surface, src/cli/guide-rays.ts): time to the first
// image (first step shown + a frame) and to the whole (last step + a frame,
// and for rays the guided passes, each a refinement and an image), frame
// ms (median of FRAMES at that camera after a discarded first), GPU peak,
// the cut's level-0 chunks and level0Fraction (covered pixels that show a
// level-0 hit).
import { readFileSync } from 'node:fs';
import { fileURLToPath } from 'node:url';
import { describeAdapter } from '../src/gpu/device.ts';
import { requestNodeGpu } from '../src/gpu/node-gpu.ts';
import { Isosurface } from '../src/isosurface/isosurface.ts';
import { ArcballCamera } from '../src/render/camera.ts';
import { RayLayer } from '../src/render/ray-layer.ts';
import { SurfaceLayer } from '../src/render/surface-layer.ts';
import { createFrameBindGroupLayout, DEPTH_FORMAT, FRAME_UNIFORM_BYTES, frameUniformData, type RenderLayer } from '../src/render/viewer.ts';
import { loadZfpStream } from '../src/zfp/gpu-stream.ts';
import { renderOffscreen } from '../src/render/offscreen.ts';
import { guideRays } from '../src/cli/guide-rays.ts';
import { destroyScene, levelPerPixel, storeScene } from '../src/cli/scene.ts';
import { meteredGpu } from '../src/gpu/memory-meter.ts';
import { openStoreInput } from '../src/store/cli-input.ts';
import { cameraForBox, fitBox0 } from '../src/store/view/camera.ts';
import { parseViewBox } from '../src/store/view/view-request.ts';
import { printTable, summarize, writeJson } from './lib/report.ts';

const here = fileURLToPath(new URL('..', import.meta.url));
const files = (process.env.FILES ?? 'bonsai_256x256x256_float32.rate4.zfp,hydrogen_atom_128x128x128_float32.rate8.zfp').split(',');
const isos = (process.env.ISOS ?? '80.37,20.37').split(',').map(Number);
const [width, height] = (process.env.SIZE ?? '1280x720').split('x').map(Number);
const frames = Number(process.env.FRAMES ?? 7);
const MiB = 2 ** 20;

const gpu = await requestNodeGpu({ label: 'rays' });
const { device } = gpu;
const adapter = describeAdapter(gpu.adapter);
const timed = device.features.has('timestamp-query');
const frameLayout = createFrameBindGroupLayout(device);
const colour = device.createTexture({ size: [width, height], format: 'rgba8unorm', usage: GPUTextureUsage.RENDER_ATTACHMENT });
const depth = device.createTexture({ size: [width, height], format: DEPTH_FORMAT, usage: GPUTextureUsage.RENDER_ATTACHMENT });
const querySet = timed ? device.createQuerySet({ type: 'timestamp', count: 2 }) : undefined;
const resolve = device.createBuffer({ size: 16, usage: GPUBufferUsage.QUERY_RESOLVE | GPUBufferUsage.COPY_SRC });
const read = device.createBuffer({ size: 16, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
const uniforms = device.createBuffer({ size: FRAME_UNIFORM_BYTES, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
const frameBindGroup = device.createBindGroup({ layout: frameLayout, entries: [{ binding: 0, resource: { buffer: uniforms } }] });

/** One frame of `layer` from `camera`: GPU ms (timestamps), else queue wall time. */
async function frameMs(layer: RenderLayer, camera: ArcballCamera): Promise<number> {
  device.queue.writeBuffer(uniforms, 0, frameUniformData(camera, width, height) as Float32Array<ArrayBuffer>);
  const encoder = device.createCommandEncoder();
  const pass = encoder.beginRenderPass({
    colorAttachments: [{ view: colour.createView(), clearValue: { r: 0, g: 0, b: 0, a: 1 }, loadOp: 'clear', storeOp: 'store' }],
    depthStencilAttachment: { view: depth.createView(), depthClearValue: 1, depthLoadOp: 'clear', depthStoreOp: 'store' },
    ...(querySet ? { timestampWrites: { querySet, beginningOfPassWriteIndex: 0, endOfPassWriteIndex: 1 } } : {}),
  });
  pass.setBindGroup(0, frameBindGroup);
  layer.draw(pass);
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

interface Row {
  volume: string;
  iso: number;
  mode: 'mesh' | 'rays';
  surfaceGpuMs: number;
  firstImageMs: number;
  frameMs: number;
  cacheBytes: number;
  vertexBytes: number;
  triangles: number;
}
const rows: Row[] = [];
for (let f = 0; f < files.length; f++) {
  const file = files[f];
  const stream = loadZfpStream(device, new Uint8Array(readFileSync(`${here}/../shared/data/volumes/${file}`)), file);
  const surface = await Isosurface.create(gpu, stream, { memoryBudgetBytes: 1536 * MiB });
  const dims = stream.info.dims;
  const camera = new ArcballCamera();
  camera.fit({ min: [0, 0, 0], max: dims.map((n) => n - 1) as [number, number, number] }, 'y');
  const target = { device, format: 'rgba8unorm' as GPUTextureFormat, frameBindGroupLayout: frameLayout, camera };
  const mesh = await SurfaceLayer.create(target);
  const rays = await RayLayer.create(target);
  // warm: pipelines made, the cache filled once at a nearby isovalue
  await surface.compute(isos[f] * 0.97);
  for (const [mode, layer] of [
    ['mesh', mesh],
    ['rays', rays],
  ] as const) {
    const stats = await surface.compute(isos[f] + (mode === 'rays' ? 0.001 : 0));
    mesh.setDrawData(surface.drawData);
    rays.setDrawData(surface.drawData);
    rays.iso = stats.isovalue;
    const first = await frameMs(layer, camera);
    const all: number[] = [];
    for (let k = 0; k <= frames; k++) {
      camera.rotateArcball(0, 0, 0.12, 0.03);
      all.push(await frameMs(layer, camera));
    }
    camera.reset();
    rows.push({
      volume: file,
      iso: stats.isovalue,
      mode,
      surfaceGpuMs: stats.gpuMs,
      firstImageMs: stats.gpuMs + first,
      frameMs: summarize(all).median,
      cacheBytes: stats.cacheBytes,
      vertexBytes: stats.vertexBytes,
      triangles: mode === 'mesh' ? stats.triangles : 0,
    });
  }
  mesh.destroy();
  rays.destroy();
  surface.destroy();
  stream.destroy();
}

interface StoreRow {
  view: string;
  mode: 'mesh' | 'rays';
  budgetMiB: number;
  firstImageMs: number;
  wholeImageMs: number;
  /** Rays: the refinements where an image's rays found the surface (guide-rays.ts). */
  guidedPasses: number;
  frameMs: number;
  gpuPeakBytes: number;
  level0Chunks: number;
  levels: string;
  level0Fraction: number;
  triangles: number;
}
const storeRows: StoreRow[] = [];
const storePath = process.env.STORE;
if (storePath) {
  const budgetMiB = Number(process.env.STORE_BUDGET ?? 256);
  const storeIso = Number(process.env.STORE_ISO ?? 2);
  const box = process.env.STORE_BOX ? parseViewBox(process.env.STORE_BOX) : undefined;
  if (typeof box === 'string') throw new Error(`STORE_BOX: ${box}`);
  for (const view of box ? (['fit', 'box'] as const) : (['fit'] as const)) {
    for (const mode of ['mesh', 'rays'] as const) {
      const { gpu: metered, meter } = meteredGpu(gpu);
      const opened = await openStoreInput(metered, storePath, {
        view: { ...(view === 'box' ? { box: box! } : { whole: true }), viewport: { width, height } },
        budget: budgetMiB * MiB,
        cacheOnly: mode === 'rays',
      });
      const surface = opened.surface;
      const t0 = performance.now();
      let firstShown: number | undefined;
      const unlisten = surface.stream.onProgress((p) => {
        if (p.phase === 'shown' && firstShown === undefined) firstShown = performance.now() - t0;
      });
      const stats = await surface.compute(storeIso);
      const whole = performance.now() - t0;
      unlisten();
      const camera = new ArcballCamera();
      const fitted = fitBox0(surface.stream.store.levels[0].layout, 0);
      const world = (v: readonly number[]) => v.map((x, a) => x * opened.voxelSize[a]) as [number, number, number];
      camera.fit({ min: world(fitted.slice(0, 3)), max: world(fitted.slice(3, 6)) }, 'y');
      camera.setState(cameraForBox(view === 'box' ? box! : fitted, opened.voxelSize, { width, height }).state);
      const target = { device, format: 'rgba8unorm' as GPUTextureFormat, frameBindGroupLayout: frameLayout, camera };
      let scene = await storeScene(target, surface, stats, mode, opened.voxelSize, [0, 0, 0]);
      const draw = (layer: RenderLayer) => renderOffscreen(device, frameLayout, camera, width, height, layer);
      // rays: refined again where the first image's rays found the surface (as `render` does)
      let guided = { passes: 0, seenChunks: 0, ms: 0 };
      if (mode === 'rays') {
        const g = await guideRays(
          surface,
          scene,
          await draw(scene.layer),
          camera,
          [width, height],
          opened.voxelSize,
          [0, 0, 0],
          (st) => storeScene(target, surface, st, mode, opened.voxelSize, [0, 0, 0]),
          draw,
          () => {},
        );
        scene = g.scene;
        guided = { passes: g.passes, seenChunks: g.seenChunks, ms: g.ms };
      }
      const all: number[] = [];
      let last: Awaited<ReturnType<typeof renderOffscreen>> | undefined;
      for (let k = 0; k <= frames; k++) {
        last = await renderOffscreen(device, frameLayout, camera, width, height, scene.layer);
        all.push(last.ms);
      }
      const pixelLevel = await levelPerPixel(
        scene,
        last!.depth,
        async (layer) => (await renderOffscreen(device, frameLayout, camera, width, height, layer)).depth,
      );
      let covered = 0;
      let level0 = 0;
      for (const L of pixelLevel) {
        if (L >= 0) covered++;
        if (L === 0) level0++;
      }
      const frame = summarize(all).median;
      storeRows.push({
        view: view === 'box' ? `box ${process.env.STORE_BOX}` : 'fit',
        mode,
        budgetMiB,
        firstImageMs: (firstShown ?? whole) + frame,
        // the view's cut and its image; rays: then the guided passes (each a refinement and its image)
        wholeImageMs: whole + frame + (mode === 'rays' ? guided.ms : 0),
        guidedPasses: guided.passes,
        frameMs: frame,
        gpuPeakBytes: meter.peak,
        level0Chunks: scene.levels.find((l) => l.level === 0)?.drawnChunks ?? 0,
        levels: scene.levels.map((l) => `${l.level}:${l.drawnChunks}`).join(' '),
        level0Fraction: covered > 0 ? level0 / covered : 0,
        triangles: mode === 'mesh' ? stats.triangles : 0,
      });
      destroyScene(scene);
      surface.destroy();
    }
  }
}

printTable(
  `triangles vs rays in the block cache, ${width}x${height}, median of ${frames} orbit frames after a discarded first (${timed ? 'GPU timestamps' : 'queue wall time'}), ${adapter}`,
  ['volume', 'iso', 'mode', 'surface GPU ms', 'first image ms', 'frame ms', 'cache MiB', 'vertex MiB (mesh only)', 'triangles'],
  rows.map((r) => [
    r.volume,
    r.iso,
    r.mode,
    r.surfaceGpuMs,
    r.firstImageMs,
    r.frameMs,
    r.cacheBytes / MiB,
    r.vertexBytes / MiB,
    r.triangles,
  ]),
);
if (storeRows.length > 0)
  printTable(
    `a store refined by the view, mesh vs rays, each planning its cut within ${storeRows[0].budgetMiB} MiB, ${width}x${height}, median of ${frames} frames after a discarded first, ${storePath}`,
    [
      'view',
      'mode',
      'first image ms',
      'whole image ms',
      'guided passes',
      'frame ms',
      'GPU peak MiB',
      'level-0 chunks',
      'cut (level:chunks)',
      'level-0 share of pixels',
      'triangles',
    ],
    storeRows.map((r) => [
      r.view,
      r.mode,
      r.firstImageMs,
      r.wholeImageMs,
      r.guidedPasses,
      r.frameMs,
      r.gpuPeakBytes / MiB,
      r.level0Chunks,
      r.levels,
      r.level0Fraction,
      r.triangles,
    ]),
  );
const name = /swiftshader/i.test(adapter)
  ? 'swiftshader'
  : adapter
      .replace(/[^a-z0-9]+/gi, '-')
      .toLowerCase()
      .slice(0, 40);
writeJson(`${here}/benchmarks/results/rays-${name}.json`, {
  adapter,
  size: [width, height],
  frames,
  timing: timed ? 'timestamp-query' : 'wall',
  note: 'volumes opened whole: the rays read the cache of a full surface computation (the same computation serves both); stores: rays over surfaces of block caches only (IsosurfaceOptions.cacheOnly)',
  rows,
  ...(storePath ? { store: storePath, storeRows } : {}),
});
