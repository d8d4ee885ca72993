// `npm run bench:surfaces` (node benchmarks/run.mjs benchmarks/surface-set.ts):
// several surfaces as the page draws them (src/app/surfaces/): each its own
// SurfaceLayer; see-through ones depth peeled (src/render/depth-peel.ts). Two
// sections (SECTIONS=core,store, both by default), the same frame code:
//
// core: one volume in core. One pipeline, the selected surface live, the
// others GPU copies. Per configuration (1 opaque surface; 2 and 4 surfaces
// with the first at opacity 0.35), off screen at SIZE x SIZE, the camera fitted:
//   - frame ms: the whole frame (opaque pass, the peels the scene needs and their composites) between
//     GPU timestamps (queue wall time without timestamp-query), median of
//     FRAMES after a discarded first;
//   - new surface ms: moving the live surface by small steps (the others stay
//     copies: nothing else is recomputed), the pipeline's GPU ms per surface,
//     median after a discarded first;
//   - GPU bytes of the copies.
// FILE (default bonsai rate 4), ISOS (4 values), SIZE, FRAMES, STEPS from the environment.
//
// store: a streamed store, opened as `extract STORE --level L` opens it
// (src/store/cli-input.ts: StoreSession, one level pinned: deterministic),
// its steps drawn as the page draws them (StoreStream snapshots on, each
// level a SurfaceLayer part at its scale and offset: StoreIsosurface.partsAt).
// STORE (a folder or URL), else a STORE_SIZE^3 uint8 ball written once by
// zarr-python with the page tests' writer (tests/fixtures/ball-store.py:
// zstd, 64^3 chunks in shards, mean pyramid, no range arrays; default 1024)
// into .cache/bench-surfaces/. LEVEL (default 1), RATE (the GPU's zfp rate
// of lossless chunks, default 8), BUDGET_MB (default: the CLI's), STORE_ISOS
// (4 values). Per configuration (1, 2, 4 surfaces, the first at opacity 0.35
// for 2 and 4; the first is the selected one, StoreStream.setIsovalue(selected,
// others)), each on a fresh session:
//   - first step ms: the cold step (every chunk fetched, every surface computed);
//   - step ms: the whole step for a new value of the selected surface (wall,
//     setIsovalue to the step shown) and its surfaces' GPU ms (the levels'
//     statistics; others kept from the step before count nothing), median of
//     STEPS after a discarded first;
//   - frame ms and peels as in core, drawing every surface of the step;
//   - chunks and bytes fetched, the stream's GPU peak (its meter) and budget.
// Then the clip: the first isovalue without a clip and with a box framing an
// eighth of the store (0..N/2 on each axis, level-0 voxels): chunks and bytes
// fetched, chunks the clip left out (StoreStream.clippedChunks), GPU peak.
//
// JSON to benchmarks/results/surface-set-<swiftshader or the GPU>.json (the
// in-core figures at the top level, the store's under `store`; a section not
// run keeps what the file held).
import { execFileSync } from 'node:child_process';
import { createHash } from 'node:crypto';
import { existsSync, mkdirSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { StoreIsosurface } from '../src/app/store/store-isosurface.ts';
import type { Clip } from '../src/core/clip.ts';
import { describeAdapter } from '../src/gpu/device.ts';
import { requestNodeGpu } from '../src/gpu/node-gpu.ts';
import { Isosurface } from '../src/isosurface/isosurface.ts';
import type { SurfaceSnapshot } from '../src/isosurface/snapshot.ts';
import { openStoreInput } from '../src/store/cli-input.ts';
import type { ChunkStoreStream } from '../src/store/gpu-port.ts';
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
const sections = (process.env.SECTIONS ?? 'core,store').split(',').map((s) => s.trim());
const MiB = 2 ** 20;

const gpu = await requestNodeGpu({ label: 'surface-set' });
const { device } = gpu;
const adapter = describeAdapter(gpu.adapter);
const timed = device.features.has('timestamp-query');
const format: GPUTextureFormat = 'rgba8unorm';
const frameLayout = createFrameBindGroupLayout(device);
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

/** A camera fitted to `max` (the box from the origin, in voxels) and its frame bind group. */
interface Scene {
  camera: ArcballCamera;
  frameBindGroup: GPUBindGroup;
  destroy(): void;
}
function sceneFor(max: [number, number, number]): Scene {
  const camera = new ArcballCamera();
  camera.fit({ min: [0, 0, 0], max });
  const uniforms = device.createBuffer({ size: FRAME_UNIFORM_BYTES, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
  device.queue.writeBuffer(uniforms, 0, frameUniformData(camera, size, size) as Float32Array<ArrayBuffer>);
  const frameBindGroup = device.createBindGroup({ layout: frameLayout, entries: [{ binding: 0, resource: { buffer: uniforms } }] });
  return { camera, frameBindGroup, destroy: () => uniforms.destroy() };
}

async function frameMs(layers: SurfaceLayer[], frameBindGroup: GPUBindGroup): Promise<number> {
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

/** FRAMES frames of `layers` after a discarded first: the median ms, and the layers the last one peeled (0: nothing see-through). */
async function timeFrames(layers: SurfaceLayer[], scene: Scene): Promise<{ frameMs: number; peels: number }> {
  const all: number[] = [];
  for (let f = 0; f <= frames; f++) all.push(await frameMs(layers, scene.frameBindGroup));
  return { frameMs: summarize(all).median, peels: peeler.lastLayers };
}

/** A layer for the scene at `opacity`. */
async function layerFor(scene: Scene, opacity: number): Promise<SurfaceLayer> {
  const layer = await SurfaceLayer.create({ device, format, frameBindGroupLayout: frameLayout, camera: scene.camera });
  layer.style.opacity = opacity;
  return layer;
}

const configs = [
  { n: 1, seeThrough: 0 },
  { n: 2, seeThrough: 1 },
  { n: 4, seeThrough: 1 },
];

// ---------------------------------------------------------------- in core
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

async function coreSection(): Promise<Record<string, unknown>> {
  const stream = loadZfpStream(device, new Uint8Array(readFileSync(`${here}/../shared/data/volumes/${file}`)), file);
  const iso = await Isosurface.create(gpu, stream, { memoryBudgetBytes: 1536 * 2 ** 20 });
  const scene = sceneFor(stream.info.dims.map((n) => n - 1) as [number, number, number]);
  const rows: Row[] = [];
  for (const { n, seeThrough } of configs) {
    // the first isovalue is the selected (live) one in every configuration, so its rows compare
    const values = [...isos.slice(1, n), isos[0]];
    const copies: SurfaceSnapshot[] = [];
    const layers: SurfaceLayer[] = [];
    let triangles = 0;
    // the others first, each copied; the last stays live
    for (let i = 0; i < n; i++) {
      const s = await iso.compute(values[i]);
      triangles += s.triangles;
      const layer = await layerFor(scene, i < seeThrough ? 0.35 : 1);
      if (i < n - 1) {
        const copy = iso.newCopy();
        iso.copyInto(copy);
        copies.push(copy);
        layer.setDrawData(copy.drawData);
      } else layer.setDrawData(iso.drawData);
      layers.push(layer);
    }
    const frame = await timeFrames(layers, scene);
    // moving the live surface: small steps around its isovalue (cache warm)
    const live = isos[0];
    const perSurface: number[] = [];
    for (let k = 0; k <= steps; k++) perSurface.push((await iso.compute(live + (k % 2 === 0 ? 1 : -1) * (1 + k) * 0.25)).gpuMs);
    rows.push({
      surfaces: n,
      seeThrough,
      triangles,
      copyBytes: copies.reduce((a, c) => a + c.byteSize, 0),
      frameMs: frame.frameMs,
      peels: frame.peels,
      newSurfaceMs: summarize(perSurface).median,
    });
    for (const l of layers) l.destroy();
    for (const c of copies) c.destroy();
  }
  printTable(
    `${file}, ${size}x${size}, isovalues ${isos.join(', ')}: median of ${frames} frames and ${steps} surfaces after a discarded first (${timed ? 'GPU timestamps' : 'queue wall time'}), ${adapter}`,
    ['surfaces', 'see-through', 'triangles', 'copies MiB', 'frame ms', 'peels', 'new surface ms'],
    rows.map((r) => [r.surfaces, r.seeThrough, r.triangles, r.copyBytes / MiB, r.frameMs, r.peels, r.newSurfaceMs]),
  );
  scene.destroy();
  iso.destroy();
  stream.destroy();
  return {
    file,
    size,
    frames,
    steps,
    isovalues: isos,
    adapter,
    timing: timed ? 'timestamp-query' : 'queue wall time',
    peelLayers: peeler.layers,
    rows,
  };
}

// ---------------------------------------------------------------- streamed store
const storeSize = Number(process.env.STORE_SIZE ?? 1024);
const level = Number(process.env.LEVEL ?? 1);
const rate = Number(process.env.RATE ?? 8);
const budget = process.env.BUDGET_MB ? Number(process.env.BUDGET_MB) * MiB : undefined;
const storeIsos = (process.env.STORE_ISOS ?? '100.5,60.5,140.5,180.5').split(',').map((v) => Math.fround(Number(v)));

/** The page tests' ball store (tests/fixtures/ball-store.py), written once per writer and size into .cache/bench-surfaces. */
async function ballStore(edge: number): Promise<string> {
  const writer = join(here, 'tests/fixtures/ball-store.py');
  const out = join(here, '.cache/bench-surfaces', `ball${edge}.zarr`);
  // made again when the writer or its arguments change (a marker holds what made it), as tests/e2e/page-budget.spec.ts does
  const made = createHash('sha256').update(readFileSync(writer)).update(`${edge} 0.3`).digest('hex');
  const marker = join(out, '.made-by');
  if (existsSync(marker) && readFileSync(marker, 'utf8') === made) return out;
  const setup = (await import(new URL('../scripts/setup/converter-env.mjs', import.meta.url).href as string)) as {
    ensureConverterEnv(root: string): string;
  };
  const python = setup.ensureConverterEnv(here);
  rmSync(out, { recursive: true, force: true });
  mkdirSync(join(here, '.cache/bench-surfaces'), { recursive: true });
  console.log(`writing ${out} (${edge}^3 uint8 ball, zstd, 64^3 chunks in shards, mean pyramid) with zarr-python...`);
  const t0 = performance.now();
  execFileSync(python, [writer, String(edge), out, '0.3'], { timeout: 3_600_000, stdio: 'inherit' });
  writeFileSync(marker, made);
  console.log(`  written in ${((performance.now() - t0) / 1000).toFixed(1)} s`);
  return out;
}

interface Opened {
  stream: ChunkStoreStream;
  record(): ReturnType<Awaited<ReturnType<typeof openStoreInput>>['record']>;
  rate: number;
  how: string;
  /** Why the refinement stopped, if it did. */
  stopped(): string | null;
  destroy(): void;
}

/** The store as `extract STORE --level L [--clip ...]` opens it; its steps drawn from copies, as the page draws them. */
async function openStream(path: string, clip?: Clip): Promise<Opened> {
  const input = await openStoreInput(gpu, path, { level, rate, ...(budget ? { budget } : {}), ...(clip ? { clip } : {}) });
  const { stream } = input.surface;
  stream.snapshots = true; // the page's steps: drawn from their copies (the CLI reads the surfaces and makes none)
  let stopped: string | null = null;
  stream.onProgress((p) => {
    if (p.phase === 'stopped') stopped = p.reason ?? 'stopped';
  });
  return { stream, record: input.record, rate: input.rate, how: input.how, stopped: () => stopped, destroy: () => input.surface.destroy() };
}

interface StepResult {
  wallMs: number;
  /** GPU ms of the surfaces this step computed (the levels' statistics; others kept from the step before count nothing). */
  gpuMs: number;
  triangles: number;
  /** Bytes of the other surfaces' copies. */
  copyBytes: number;
}

/** One whole step: `iso` selected, `others` drawn with it, refined to the end of the pinned level's plan. */
async function step(o: Opened, iso: number, others: readonly number[]): Promise<StepResult> {
  const before = new Set((o.stream.shown?.levels ?? []).flatMap((l) => l.others.map((x) => x.copy)));
  const t0 = performance.now();
  await o.stream.setIsovalue(iso, others);
  const wallMs = performance.now() - t0;
  await o.stream.learnSettled(); // as the CLI: the next isovalue plans with the ranges this one's chunks taught
  const s = o.stream.shown;
  if (!s?.final || s.iso !== iso || s.levels.length === 0 || !s.levels.every((l) => l.level === level))
    throw new Error(`level ${level} at isovalue ${iso} was not reached: ${o.stopped() ?? 'no step on screen'}`);
  let gpuMs = 0;
  let triangles = 0;
  let copyBytes = 0;
  for (const l of s.levels) {
    gpuMs += l.stats.gpuMs;
    triangles += l.stats.triangles;
    for (const x of l.others) {
      if (!before.has(x.copy)) gpuMs += x.stats.gpuMs;
      triangles += x.stats.triangles;
      copyBytes += x.copy.byteSize;
    }
  }
  return { wallMs, gpuMs, triangles, copyBytes };
}

interface StoreRow {
  surfaces: number;
  seeThrough: number;
  triangles: number;
  /** Bytes of the other surfaces' copies (the selected one's drawn copy is in the GPU peak). */
  copyBytes: number;
  /** The first, cold step: every chunk fetched, every surface computed. */
  firstStepMs: number;
  /** A new value of the selected surface: the whole step, wall, and its surfaces' GPU ms (medians). */
  stepMs: number;
  stepGpuMs: number;
  frameMs: number;
  peels: number;
  /** Distinct chunks of the level fetched, their bytes as they came, everything through the store (metadata, shard indexes). */
  chunks: number;
  levelChunks: number;
  chunkBytes: number;
  bytesFetched: number;
  gpuPeakBytes: number;
  budgetBytes: number;
}

interface ClipRow {
  clip: string;
  triangles: number;
  stepMs: number;
  chunks: number;
  chunkBytes: number;
  bytesFetched: number;
  clippedChunks: number;
  gpuPeakBytes: number;
}

async function storeSection(): Promise<Record<string, unknown>> {
  const path = process.env.STORE ?? (await ballStore(storeSize));
  const rows: StoreRow[] = [];
  let how = '';
  let dims: [number, number, number] = [0, 0, 0];
  for (const { n, seeThrough } of configs) {
    const o = await openStream(path);
    how = o.how;
    dims = [...o.stream.levels[0].layout.dims] as [number, number, number];
    const scene = sceneFor(dims.map((d) => d - 1) as [number, number, number]);
    // the first isovalue is the selected one in every configuration, so its rows compare
    const values = storeIsos.slice(0, n);
    const live = values[0];
    const others = values.slice(1);
    const first = await step(o, live, others);
    // each surface a layer drawing the step's pieces at its isovalue, as the page's
    const page = new StoreIsosurface(
      o.stream,
      o.stream.shown!,
      o.stream.valueRange ?? [0, 0],
      (v, w) => o.stream.setIsovalue(v, w),
      (seen) => o.stream.setSeen(seen),
      () => {},
    );
    const layers: SurfaceLayer[] = [];
    for (let i = 0; i < n; i++) {
      const layer = await layerFor(scene, i < seeThrough ? 0.35 : 1);
      layer.setParts(page.partsAt(values[i]));
      layers.push(layer);
    }
    const frame = await timeFrames(layers, scene);
    for (const l of layers) l.destroy();
    // a new value of the selected surface: small steps around it, the others drawn with each
    const moved: StepResult[] = [];
    for (let k = 0; k <= steps; k++) moved.push(await step(o, Math.fround(live + (k % 2 === 0 ? 1 : -1) * (1 + k)), others));
    const r = o.record();
    rows.push({
      surfaces: n,
      seeThrough,
      triangles: first.triangles,
      copyBytes: first.copyBytes,
      firstStepMs: first.wallMs,
      stepMs: summarize(moved.map((m) => m.wallMs)).median,
      stepGpuMs: summarize(moved.map((m) => m.gpuMs)).median,
      frameMs: frame.frameMs,
      peels: frame.peels,
      chunks: r.chunks,
      levelChunks: r.levelChunks,
      chunkBytes: r.chunkBytesFetched,
      bytesFetched: r.bytesFetched,
      gpuPeakBytes: r.gpuPeakBytes,
      budgetBytes: r.budgetBytes,
    });
    page.destroy();
    scene.destroy();
    o.destroy();
  }
  const name = process.env.STORE ?? `ball ${storeSize}^3 uint8 (tests/fixtures/ball-store.py)`;
  printTable(
    `${name}, level ${level} pinned, ${size}x${size}, isovalues ${storeIsos.join(', ')} (the first selected): median of ${frames} frames and ${steps} steps after a discarded first, ${adapter}`,
    [
      'surfaces',
      'see-through',
      'triangles',
      'copies MiB',
      'first step ms',
      'step ms',
      'step GPU ms',
      'frame ms',
      'peels',
      'chunks',
      'chunk MiB',
      'fetched MiB',
      'GPU peak MiB',
    ],
    rows.map((r) => [
      r.surfaces,
      r.seeThrough,
      r.triangles,
      r.copyBytes / MiB,
      r.firstStepMs,
      r.stepMs,
      r.stepGpuMs,
      r.frameMs,
      r.peels,
      `${r.chunks}/${r.levelChunks}`,
      r.chunkBytes / MiB,
      r.bytesFetched / MiB,
      r.gpuPeakBytes / MiB,
    ]),
  );

  // the clip: one isovalue, without and with a box framing an eighth of the store
  const eighth: Clip = { box: [0, 0, 0, dims[0] / 2, dims[1] / 2, dims[2] / 2] };
  const clipRows: ClipRow[] = [];
  for (const clip of [undefined, eighth]) {
    const o = await openStream(path, clip);
    const s = await step(o, storeIsos[0], []);
    const r = o.record();
    clipRows.push({
      clip: clip?.box ? `box ${clip.box.join(',')}` : 'none',
      triangles: s.triangles,
      stepMs: s.wallMs,
      chunks: r.chunks,
      chunkBytes: r.chunkBytesFetched,
      bytesFetched: r.bytesFetched,
      clippedChunks: r.clippedChunks,
      gpuPeakBytes: r.gpuPeakBytes,
    });
    o.destroy();
  }
  const [whole, clipped] = clipRows;
  const saved = {
    chunks: whole.chunks - clipped.chunks,
    bytes: whole.bytesFetched - clipped.bytesFetched,
    fraction: whole.bytesFetched > 0 ? 1 - clipped.bytesFetched / whole.bytesFetched : 0,
    gpuPeakBytes: whole.gpuPeakBytes - clipped.gpuPeakBytes,
  };
  printTable(
    `${name}, level ${level} pinned, isovalue ${storeIsos[0]}: a clip box framing an eighth (level-0 voxels; triangles: those computed, the renderer cuts the rest)`,
    ['clip', 'triangles', 'step ms', 'chunks', 'chunk MiB', 'fetched MiB', 'clipped chunks', 'GPU peak MiB'],
    clipRows.map((r) => [
      r.clip,
      r.triangles,
      r.stepMs,
      r.chunks,
      r.chunkBytes / MiB,
      r.bytesFetched / MiB,
      r.clippedChunks,
      r.gpuPeakBytes / MiB,
    ]),
  );
  console.log(
    `the clip box saves ${saved.chunks} chunks, ${(saved.bytes / MiB).toFixed(2)} MiB fetched (${(100 * saved.fraction).toFixed(1)}%), ${(saved.gpuPeakBytes / MiB).toFixed(1)} MiB of GPU peak`,
  );
  return {
    store: process.env.STORE ?? null,
    generated: process.env.STORE ? null : { writer: 'tests/fixtures/ball-store.py', edge: storeSize, radius: 0.3 },
    how,
    dims,
    level,
    rate,
    size,
    frames,
    steps,
    isovalues: storeIsos,
    selected: 'the first isovalue in every configuration',
    timing: {
      step: "wall ms from setIsovalue to its step shown (learnt ranges settled after, untimed); GPU ms: the step's surfaces' statistics",
      frame: timed ? 'timestamp-query' : 'queue wall time',
    },
    rows,
    clip: { isovalue: storeIsos[0], box: eighth.box, rows: clipRows, saved },
  };
}

const out = `${here}/benchmarks/results/surface-set-${/swiftshader/i.test(adapter) ? 'swiftshader' : adapter.split(' / ')[0].replace(/\W+/g, '-').toLowerCase()}.json`;
// a section not run keeps what the file held
let result: Record<string, unknown> = {};
if (existsSync(out)) {
  try {
    result = JSON.parse(readFileSync(out, 'utf8')) as Record<string, unknown>;
  } catch {
    result = {};
  }
}
if (sections.includes('core')) result = { ...(await coreSection()), ...(result.store ? { store: result.store } : {}) };
if (sections.includes('store')) result.store = await storeSection();
writeJson(out, result);
peeler.destroy();
device.destroy();
