// Depth peeling against a CPU compositing reference: three nested spheres
// (an opaque one inside two at opacity 0.5) drawn on Dawn with SurfaceLayer
// and DepthPeeler, each in one flat colour (saturating ambient light, no
// specular, rim or depth cue, so the GPU's colour of a fragment is known
// exactly), compared per pixel with the same meshes rasterized on the CPU:
// every fragment at every pixel centre, the opaque nearest hides what is
// behind it, the rest composited back to front. The triangles are drawn in
// their marching-cubes order, which is not depth order: blending in
// submission order would not match. With one peel only, the image differs.
import { describe, expect } from 'vitest';
import { mat4, vec4 } from 'gl-matrix';
import { ArcballCamera } from '../../../src/render/camera.ts';
import { DepthPeeler } from '../../../src/render/depth-peel.ts';
import { SurfaceLayer } from '../../../src/render/surface-layer.ts';
import { createCpuSurface } from '../../../src/render/testing/cpu-surface.ts';
import { createFrameBindGroupLayout, DEPTH_FORMAT, FRAME_UNIFORM_BYTES, frameUniformData } from '../../../src/render/viewer.ts';
import type { Dims } from '../../../src/core/naming.ts';
import { marchingCubes } from '../../../src/mc/serial-mc.ts';
import { gpuTest } from '../../helpers/gpu.ts';

const N = 32;
const W = 96;
const H = 80;
const BACKGROUND = [0.2, 0.2, 0.2];

function sphereVolume(): Float32Array {
  const v = new Float32Array(N * N * N);
  const c = (N - 1) / 2;
  for (let z = 0; z < N; z++)
    for (let y = 0; y < N; y++) for (let x = 0; x < N; x++) v[x + N * (y + N * z)] = 20 - Math.hypot(x - c, y - c, z - c);
  return v;
}

interface Sphere {
  iso: number;
  colour: [number, number, number];
  opacity: number;
}
// radii 3 (opaque blue), 6 (green) and 12 (red), listed outermost last so the inner ones are drawn first
const SPHERES: Sphere[] = [
  { iso: 17, colour: [0, 0, 1], opacity: 1 },
  { iso: 14, colour: [0, 1, 0], opacity: 0.5 },
  { iso: 8, colour: [1, 0, 0], opacity: 0.5 },
];

/** Every fragment at each pixel centre: NDC depth, sphere index (a CPU rasterizer, perspective-correct depth as the GPU's). */
function cpuFragments(values: Float32Array, viewProj: mat4): { z: number; s: number }[][] {
  const frags: { z: number; s: number }[][] = Array.from({ length: W * H }, () => []);
  const p = vec4.create();
  SPHERES.forEach((sphere, s) => {
    const soup = marchingCubes(values, [N, N, N], sphere.iso).positions;
    for (let t = 0; t < soup.length; t += 9) {
      const sx: number[] = [],
        sy: number[] = [],
        sz: number[] = [];
      for (let v = 0; v < 3; v++) {
        vec4.transformMat4(p, [soup[t + 3 * v], soup[t + 3 * v + 1], soup[t + 3 * v + 2], 1], viewProj);
        sx.push(((p[0] / p[3] + 1) / 2) * W);
        sy.push(((1 - p[1] / p[3]) / 2) * H);
        sz.push(p[2] / p[3]);
      }
      const area = (sx[1] - sx[0]) * (sy[2] - sy[0]) - (sx[2] - sx[0]) * (sy[1] - sy[0]);
      if (area === 0) continue;
      const x0 = Math.max(0, Math.floor(Math.min(...sx))),
        x1 = Math.min(W - 1, Math.ceil(Math.max(...sx)));
      const y0 = Math.max(0, Math.floor(Math.min(...sy))),
        y1 = Math.min(H - 1, Math.ceil(Math.max(...sy)));
      for (let y = y0; y <= y1; y++) {
        for (let x = x0; x <= x1; x++) {
          const px = x + 0.5,
            py = y + 0.5;
          const w0 = ((sx[1] - px) * (sy[2] - py) - (sx[2] - px) * (sy[1] - py)) / area;
          const w1 = ((sx[2] - px) * (sy[0] - py) - (sx[0] - px) * (sy[2] - py)) / area;
          const w2 = 1 - w0 - w1;
          if (w0 < 0 || w1 < 0 || w2 < 0) continue;
          // NDC depth is affine in screen space
          frags[x + W * y].push({ z: w0 * sz[0] + w1 * sz[1] + w2 * sz[2], s });
        }
      }
    }
  });
  return frags;
}

function cpuComposite(frags: { z: number; s: number }[][]): Float64Array {
  const out = new Float64Array(W * H * 3);
  frags.forEach((list, i) => {
    let opaqueZ = Infinity;
    let c = [...BACKGROUND];
    for (const f of list) {
      if (SPHERES[f.s].opacity === 1 && f.z < opaqueZ) {
        opaqueZ = f.z;
        c = [...SPHERES[f.s].colour];
      }
    }
    const see = list.filter((f) => SPHERES[f.s].opacity < 1 && f.z < opaqueZ).sort((a, b) => b.z - a.z);
    for (const f of see) {
      const { colour, opacity } = SPHERES[f.s];
      c = c.map((v, k) => opacity * colour[k] + (1 - opacity) * v);
    }
    out.set(c, 3 * i);
  });
  return out;
}

async function renderGpu(
  device: GPUDevice,
  layers: SurfaceLayer[],
  camera: ArcballCamera,
  peelLayers: number,
  given?: DepthPeeler,
): Promise<Uint8Array> {
  const format: GPUTextureFormat = 'rgba8unorm';
  const frameLayout = createFrameBindGroupLayout(device);
  const peeler = given ?? (await DepthPeeler.create(device, format));
  peeler.layers = peelLayers;
  const colour = device.createTexture({ size: [W, H], format, usage: GPUTextureUsage.RENDER_ATTACHMENT | GPUTextureUsage.COPY_SRC });
  const depth = device.createTexture({
    size: [W, H],
    format: DEPTH_FORMAT,
    usage: GPUTextureUsage.RENDER_ATTACHMENT | GPUTextureUsage.TEXTURE_BINDING,
  });
  const uniforms = device.createBuffer({ size: FRAME_UNIFORM_BYTES, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
  device.queue.writeBuffer(uniforms, 0, frameUniformData(camera, W, H) as Float32Array<ArrayBuffer>);
  const frameBindGroup = device.createBindGroup({ layout: frameLayout, entries: [{ binding: 0, resource: { buffer: uniforms } }] });
  const bytesPerRow = 256 * Math.ceil((W * 4) / 256);
  const read = device.createBuffer({ size: bytesPerRow * H, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
  const encoder = device.createCommandEncoder();
  const target = colour.createView();
  const depthView = depth.createView();
  const [r, g, b] = BACKGROUND;
  const pass = encoder.beginRenderPass({
    colorAttachments: [{ view: target, clearValue: { r, g, b, a: 1 }, loadOp: 'clear', storeOp: 'store' }],
    depthStencilAttachment: { view: depthView, depthClearValue: 1, depthLoadOp: 'clear', depthStoreOp: 'store' },
  });
  pass.setBindGroup(0, frameBindGroup);
  for (const l of layers) l.draw(pass);
  pass.end();
  expect(DepthPeeler.anyTransparent(layers)).toBe(true);
  peeler.encode(encoder, { target, opaqueDepth: depthView, width: W, height: H, frameBindGroup, layers });
  encoder.copyTextureToBuffer({ texture: colour }, { buffer: read, bytesPerRow }, [W, H]);
  device.queue.submit([encoder.finish()]);
  await read.mapAsync(GPUMapMode.READ);
  const rows = new Uint8Array(read.getMappedRange());
  const out = new Uint8Array(W * H * 4);
  for (let y = 0; y < H; y++) out.set(rows.subarray(y * bytesPerRow, y * bytesPerRow + W * 4), y * W * 4);
  for (const x of [colour, depth, uniforms, read]) x.destroy();
  if (!given) peeler.destroy();
  return out;
}

/** Pixels whose colour differs from the reference by more than 3/255 in a channel. */
function mismatches(gpu: Uint8Array, ref: Float64Array): number {
  let n = 0;
  for (let i = 0; i < W * H; i++) {
    for (let k = 0; k < 3; k++) {
      if (Math.abs(gpu[4 * i + k] - 255 * ref[3 * i + k]) > 3) {
        n++;
        break;
      }
    }
  }
  return n;
}

describe('DepthPeeler', () => {
  gpuTest('nested see-through spheres composite as exact back-to-front (CPU reference)', async ({ gpu }) => {
    const { device } = gpu;
    const values = sphereVolume();
    const dims: Dims = [N, N, N];
    const camera = new ArcballCamera();
    camera.fit({ min: [0, 0, 0], max: [N - 1, N - 1, N - 1] });
    camera.setState({ ...camera.getState(), rotation: [0.2, 0.35, 0.05, 0.91] });
    const frameLayout = createFrameBindGroupLayout(device);
    const surfaces = SPHERES.map((s) => createCpuSurface(device, values, dims, s.iso));
    const layers = await Promise.all(
      SPHERES.map(async (s, i) => {
        const layer = await SurfaceLayer.create({ device, format: 'rgba8unorm', frameBindGroupLayout: frameLayout, camera });
        layer.setDrawData(surfaces[i].data);
        Object.assign(layer.style, {
          front: s.colour,
          back: s.colour,
          smooth: false,
          ambient: 1,
          specular: 0,
          rim: 0,
          depthCue: 0,
          opacity: s.opacity,
        });
        return layer;
      }),
    );
    camera.aspect = W / H;
    const reference = cpuComposite(cpuFragments(values, camera.viewProjection(mat4.create())));

    const image = await renderGpu(device, layers, camera, 8);
    const bad = mismatches(image, reference);
    // the centre ray: red in front, green, then the opaque blue: 0.5 red + 0.25 green + 0.25 blue
    const centre = 4 * (W / 2 + W * (H / 2));
    expect([...image.subarray(centre, centre + 3)].map((v) => Math.round(v / 255 / 0.25))).toEqual([2, 1, 1]);
    // pixel centres on triangle edges and silhouettes may fall either way: at most 0.2% of the pixels (1 here;
    // blending each layer over instead of under gives 53)
    expect(bad, `${bad} of ${W * H} pixels differ`).toBeLessThanOrEqual(0.002 * W * H);
    // adaptive (the page's): the first frame peels all 8, the next ones one past the deepest that drew (4 here)
    const adaptive = await DepthPeeler.create(device, 'rgba8unorm');
    adaptive.adaptive = true;
    for (let frame = 0; frame < 3; frame++) {
      const img = await renderGpu(device, layers, camera, 8, adaptive);
      await new Promise((r) => setTimeout(r, 50)); // the counts are read back after the frame
      expect(mismatches(img, reference)).toBe(bad);
    }
    expect(adaptive.lastLayers).toBe(5);
    adaptive.destroy();
    // one peel keeps only the nearest layer: far from the reference
    expect(mismatches(await renderGpu(device, layers, camera, 1), reference)).toBeGreaterThan(0.05 * W * H);

    for (const l of layers) l.destroy();
    for (const s of surfaces) s.destroy();
  });
});
