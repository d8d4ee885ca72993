// Caps against NumPy: the cap of a clip plane through a published zfp
// volume, drawn on Dawn, has at every pixel the colour map of NumPy's
// trilinear value of zfpy's decode at the point where the pixel's ray meets
// the plane (background where that value is under the threshold or the
// point is outside the volume). An oblique plane as well as an axis plane.
// A store's caps too: pieces from the pool of a stream's step with caps on
// (the chunks along the cut fetched for them), the same image as NumPy's
// over zfpy's decode of the level compressed at the store's rate.
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { mat4 } from 'gl-matrix';
import { describe, expect } from 'vitest';
import type { Clip } from '../../../src/core/clip.ts';
import { ArcballCamera } from '../../../src/render/camera.ts';
import { CapLayer } from '../../../src/render/cap-layer.ts';
import { createFrameBindGroupLayout, DEPTH_FORMAT, FRAME_UNIFORM_BYTES, frameUniformData, unproject } from '../../../src/render/viewer.ts';
import { loadZfpStream } from '../../../src/zfp/gpu-stream.ts';
import { storeCapPieces } from '../../../src/app/store/store-caps.ts';
import { ChunkFetcher } from '../../../src/store/fetch/chunk-fetcher.ts';
import { createChunkStream } from '../../../src/store/gpu-port.ts';
import { storeForLocation } from '../../../src/store/zarr/node-store.ts';
import { openStore } from '../../../src/store/zarr/open-store.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { repoRoot, runPython, sharedData } from '../../helpers/python.ts';

const W = 96;
const H = 96;
const THRESHOLD = 3;
const RANGE: [number, number] = [0, 60];

describe('CapLayer', () => {
  gpuTest('a cap shows the colour-mapped slice of the decoded volume (NumPy over zfpy)', async ({ gpu }) => {
    const { device } = gpu;
    const file = join(sharedData, 'volumes/hydrogen_atom_128x128x128_float32.rate8.zfp');
    const stream = loadZfpStream(device, new Uint8Array(readFileSync(file)), file);
    const frameLayout = createFrameBindGroupLayout(device);
    const camera = new ArcballCamera();
    camera.fit({ min: [0, 0, 0], max: [127, 127, 127] });
    camera.setState({ ...camera.getState(), rotation: [0.15, 0.2, 0.02, 0.968] });
    const layer = await CapLayer.create({ device, format: 'rgba8unorm', frameBindGroupLayout: frameLayout, camera });
    layer.threshold = THRESHOLD;
    layer.range = RANGE;
    for (const plane of [
      { normal: [0, 0, 1], d: 64.5 },
      { normal: [0.3, -0.2, 0.93], d: 63 },
    ] as Clip['plane'][]) {
      layer.setClip(stream, { plane });
      expect(layer.blocks).toBeGreaterThan(0);
      await expectCapImage(device, layer, camera, frameLayout, plane!, `zfpy.decompress_numpy(open('${file}', 'rb').read())`);
    }
    // caps that do not fit what the budget leaves are not made, and say why
    expect(layer.setClip(stream, { plane: { normal: [0, 0, 1], d: 64.5 } }, 1000)).toMatch(
      /^the caps need [\d.]+ MiB for the [\d,]+ blocks along the cut/,
    );
    expect(layer.blocks).toBe(0);
    expect(layer.byteSize).toBe(0);
    layer.destroy();
    stream.destroy();
  });

  gpuTest("a store's caps: a piece per level of the step from its pool, the chunks along the cut fetched for them", async ({ gpu }) => {
    const { device } = gpu;
    const work = mkdtempSync(join(tmpdir(), 'store-caps-'));
    const path = join(work, 'ball.zarr');
    // a ball 64^3 (NumPy), in chunks of 8^3: the surface's 27-neighbourhoods leave chunks deep inside it
    const raw = join(work, 'ball_64x64x64_float32.raw');
    runPython(
      `
import sys, numpy as np
z, y, x = np.mgrid[0:64, 0:64, 0:64].astype(np.float64)
r = np.sqrt((x - 31.5) ** 2 + (y - 30) ** 2 + (z - 33) ** 2)
f = 60 * np.clip(1 - r / 28, 0, 1) + 4 * np.sin(x / 5) * np.cos(y / 7)
f.astype(np.float32).tofile(sys.argv[1])
`,
      [raw],
    );
    execFileSync(
      process.execPath,
      [join(repoRoot, 'scripts/convert.mjs'), raw, '--out', path, '--quiet', '--chunk', '8', '--rate', '8', '--levels', '1'],
      {
        cwd: repoRoot,
        stdio: 'pipe',
      },
    );
    const store = await openStore(storeForLocation(path), path);
    const fetcher = new ChunkFetcher(store, { maxInFlight: 8 });
    const c = await createChunkStream(store, fetcher, gpu, 256 << 20);
    const plane = { normal: [0.1, 0, 1], d: 35.5 } as const;
    c.stream.finest = 0;
    c.stream.coarsest = 0;
    c.stream.setClip({ plane });
    // the surface at the caps' threshold: without caps, the chunks deep inside it (no surface in their
    // neighbourhood) are not fetched, and the cap would have holes there
    await c.setIsovalue(THRESHOLD);
    const withoutCaps = fetcher.counters.bytesFetched;
    c.stream.setCaps(true);
    await c.setIsovalue(THRESHOLD);
    expect(fetcher.counters.bytesFetched).toBeGreaterThan(withoutCaps);
    const frameLayout = createFrameBindGroupLayout(device);
    const camera = new ArcballCamera();
    camera.fit({ min: [0, 0, 0], max: [63, 63, 63] });
    camera.setState({ ...camera.getState(), rotation: [0.15, 0.2, 0.02, 0.968] });
    const layer = await CapLayer.create({ device, format: 'rgba8unorm', frameBindGroupLayout: frameLayout, camera });
    layer.threshold = THRESHOLD;
    layer.range = RANGE;
    expect(layer.setPieces(storeCapPieces(store, c.stream.shown!, { plane }))).toBeNull();
    expect(layer.pieces).toBe(1);
    await expectCapImage(
      device,
      layer,
      camera,
      frameLayout,
      plane,
      `zfpy.decompress_numpy(zfpy.compress_numpy(np.fromfile('${raw}', dtype=np.float32).reshape(64, 64, 64), rate=8))`,
      64,
    );
    layer.destroy();
    c.destroy();
    rmSync(work, { recursive: true, force: true });
  });
});

/** The cap of `plane` drawn by `layer` against NumPy's colour-mapped trilinear values of the volume `load` (Python, z y x) gives. */
async function expectCapImage(
  device: GPUDevice,
  layer: CapLayer,
  camera: ArcballCamera,
  frameLayout: GPUBindGroupLayout,
  plane: NonNullable<Clip['plane']>,
  load: string,
  size = 128,
): Promise<void> {
  {
    const image = await render(device, layer, camera, frameLayout);
    // each pixel's ray meets the plane at
    camera.aspect = W / H;
    const viewProj = camera.viewProjection(mat4.create());
    const points: (number[] | null)[] = [];
    for (let y = 0; y < H; y++) {
      for (let x = 0; x < W; x++) {
        const ndc = [((x + 0.5) / W) * 2 - 1, 1 - ((y + 0.5) / H) * 2];
        const a = unproject(viewProj, [...ndc, 0]);
        const b = unproject(viewProj, [...ndc, 1]);
        const n = plane.normal;
        const fa = n[0] * a[0] + n[1] * a[1] + n[2] * a[2] - plane.d;
        const fb = n[0] * b[0] + n[1] * b[1] + n[2] * b[2] - plane.d;
        const t = fa / (fa - fb);
        const p = a.map((v, k) => v + t * (b[k] - v));
        points.push(fa * fb < 0 && p.every((v) => v >= 0 && v <= size - 1) ? p : null);
      }
    }
    const pointsFile = join(mkdtempSync(join(tmpdir(), 'caps-')), 'points.json');
    writeFileSync(pointsFile, JSON.stringify(points));
    const expected: (number[] | null)[] = JSON.parse(
      runPython(
        `
import sys, json, zfpy, numpy as np
v = (${load}).astype(np.float64)   # z, y, x
stops = np.array([[0.15, 0.1, 0.4], [0.2, 0.35, 0.6], [0.15, 0.6, 0.55], [0.5, 0.8, 0.3], [0.98, 0.9, 0.15]])
lo_v, hi_v, threshold = float(sys.argv[3]), float(sys.argv[4]), float(sys.argv[5])
out = []
for p in json.load(open(sys.argv[2])):
    if p is None:
        out.append(None); continue
    lo = [min(max(int(np.floor(p[a])), 0), v.shape[2 - a] - 2) for a in range(3)]
    f = [p[a] - lo[a] for a in range(3)]
    s = sum(np.prod([f[a] if (k >> a) & 1 else 1 - f[a] for a in range(3)]) * v[lo[2] + ((k >> 2) & 1), lo[1] + ((k >> 1) & 1), lo[0] + (k & 1)] for k in range(8))
    if s < threshold:
        out.append(None); continue
    x = min(max((s - lo_v) / (hi_v - lo_v), 0), 1) * 4
    i = min(int(np.floor(x)), 3)
    out.append((stops[i] + (x - i) * (stops[i + 1] - stops[i])).tolist())
print(json.dumps(out))
`,
        ['', pointsFile, String(RANGE[0]), String(RANGE[1]), String(THRESHOLD)],
      ),
    );
    let covered = 0;
    let bad = 0;
    expected.forEach((c, i) => {
      const got = [image[4 * i], image[4 * i + 1], image[4 * i + 2]];
      const want = c ? c.map((v) => Math.round(255 * v)) : [0, 0, 0];
      if (c) covered++;
      if (got.some((g, k) => Math.abs(g - want[k]) > 2)) bad++;
    });
    expect(covered).toBeGreaterThan(0.05 * W * H);
    // pixels on the threshold's outline or the polygon's edge may fall either way
    expect(bad, `${bad} of ${W * H} pixels differ (${covered} on the cap)`).toBeLessThan(0.02 * covered);
  }
}

async function render(device: GPUDevice, layer: CapLayer, camera: ArcballCamera, layout: GPUBindGroupLayout): Promise<Uint8Array> {
  const colour = device.createTexture({
    size: [W, H],
    format: 'rgba8unorm',
    usage: GPUTextureUsage.RENDER_ATTACHMENT | GPUTextureUsage.COPY_SRC,
  });
  const depth = device.createTexture({ size: [W, H], format: DEPTH_FORMAT, usage: GPUTextureUsage.RENDER_ATTACHMENT });
  const uniforms = device.createBuffer({ size: FRAME_UNIFORM_BYTES, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
  device.queue.writeBuffer(uniforms, 0, frameUniformData(camera, W, H) as Float32Array<ArrayBuffer>);
  const group = device.createBindGroup({ layout, entries: [{ binding: 0, resource: { buffer: uniforms } }] });
  const bytesPerRow = 256 * Math.ceil((4 * W) / 256);
  const read = device.createBuffer({ size: bytesPerRow * H, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
  const encoder = device.createCommandEncoder();
  const pass = encoder.beginRenderPass({
    colorAttachments: [{ view: colour.createView(), clearValue: { r: 0, g: 0, b: 0, a: 1 }, loadOp: 'clear', storeOp: 'store' }],
    depthStencilAttachment: { view: depth.createView(), depthClearValue: 1, depthLoadOp: 'clear', depthStoreOp: 'store' },
  });
  pass.setBindGroup(0, group);
  layer.draw(pass);
  pass.end();
  encoder.copyTextureToBuffer({ texture: colour }, { buffer: read, bytesPerRow }, [W, H]);
  device.queue.submit([encoder.finish()]);
  await read.mapAsync(GPUMapMode.READ);
  const rows = new Uint8Array(read.getMappedRange());
  const out = new Uint8Array(4 * W * H);
  for (let y = 0; y < H; y++) out.set(rows.subarray(y * bytesPerRow, y * bytesPerRow + 4 * W), 4 * W * y);
  for (const x of [colour, depth, uniforms, read]) x.destroy();
  return out;
}
