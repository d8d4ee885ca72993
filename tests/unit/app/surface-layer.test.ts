// The surface renderer on Dawn, off screen: a sphere's isosurface is drawn
// lit in the outside colour from outside and in the inside colour from
// within; gradient normals shade it smoothly where flat normals show facets;
// normals from uncached neighbour blocks (one-sided differences) still shade sensibly;
// anisotropic voxels put it where the camera's projection of the scaled soup
// is; the depth-only pass writes exactly the depths the lit pass draws at.
import { mat4, vec4 } from 'gl-matrix';
import { describe, expect } from 'vitest';
import { ArcballCamera } from '../../../src/render/camera.ts';
import { SurfaceLayer } from '../../../src/render/surface-layer.ts';
import { createCpuSurface } from '../../../src/render/testing/cpu-surface.ts';
import { createFrameBindGroupLayout, DEPTH_FORMAT, FRAME_UNIFORM_BYTES, frameUniformData } from '../../../src/render/viewer.ts';
import type { Dims } from '../../../src/core/naming.ts';
import { marchingCubes } from '../../../src/mc/serial-mc.ts';
import { gpuTest } from '../../helpers/gpu.ts';

const SIZE = 128;

function sphereVolume(n: number): Float32Array {
  // Values decrease outward (inside = value >= iso), like a density.
  const v = new Float32Array(n * n * n);
  const c = (n - 1) / 2;
  for (let z = 0; z < n; z++)
    for (let y = 0; y < n; y++) for (let x = 0; x < n; x++) v[x + n * (y + n * z)] = 20 - Math.hypot(x - c, y - c, z - c);
  return v;
}

/** The layer drawn into a SIZE x SIZE image; with `prepass`, its depth alone first into the same depth buffer. */
async function render(
  device: GPUDevice,
  layer: SurfaceLayer,
  camera: ArcballCamera,
  layout: GPUBindGroupLayout,
  prepass = false,
): Promise<Uint8Array> {
  const color = device.createTexture({
    size: [SIZE, SIZE],
    format: 'rgba8unorm',
    usage: GPUTextureUsage.RENDER_ATTACHMENT | GPUTextureUsage.COPY_SRC,
  });
  const depth = device.createTexture({ size: [SIZE, SIZE], format: DEPTH_FORMAT, usage: GPUTextureUsage.RENDER_ATTACHMENT });
  const uniforms = device.createBuffer({ size: FRAME_UNIFORM_BYTES, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
  device.queue.writeBuffer(uniforms, 0, frameUniformData(camera, SIZE, SIZE) as Float32Array<ArrayBuffer>);
  const group = device.createBindGroup({ layout, entries: [{ binding: 0, resource: { buffer: uniforms } }] });
  const read = device.createBuffer({ size: SIZE * SIZE * 4, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
  const encoder = device.createCommandEncoder();
  if (prepass) {
    const depthPass = encoder.beginRenderPass({
      colorAttachments: [],
      depthStencilAttachment: { view: depth.createView(), depthClearValue: 1, depthLoadOp: 'clear', depthStoreOp: 'store' },
    });
    depthPass.setBindGroup(0, group);
    layer.drawDepth(depthPass);
    depthPass.end();
  }
  const pass = encoder.beginRenderPass({
    colorAttachments: [{ view: color.createView(), clearValue: { r: 0, g: 0, b: 0, a: 1 }, loadOp: 'clear', storeOp: 'store' }],
    depthStencilAttachment: {
      view: depth.createView(),
      depthClearValue: 1,
      depthLoadOp: prepass ? 'load' : 'clear',
      depthStoreOp: 'store',
    },
  });
  pass.setBindGroup(0, group);
  layer.draw(pass);
  pass.end();
  encoder.copyTextureToBuffer({ texture: color }, { buffer: read, bytesPerRow: SIZE * 4 }, [SIZE, SIZE]);
  device.queue.submit([encoder.finish()]);
  await read.mapAsync(GPUMapMode.READ);
  const out = new Uint8Array(read.getMappedRange().slice(0));
  for (const r of [color, depth, uniforms, read]) r.destroy();
  return out;
}

const px = (img: Uint8Array, x: number, y: number) => [img[4 * (x + SIZE * y)], img[4 * (x + SIZE * y) + 1], img[4 * (x + SIZE * y) + 2]];
const lum = (img: Uint8Array, x: number, y: number) => px(img, x, y).reduce((a, b) => a + b, 0);

/** Largest brightness step between neighbouring pixels inside the sphere's disc (away from its outline). */
function largestStep(img: Uint8Array): number {
  let worst = 0;
  for (let y = SIZE / 2 - 12; y < SIZE / 2 + 12; y++) {
    for (let x = SIZE / 2 - 12; x < SIZE / 2 + 12; x++) {
      const a = lum(img, x, y),
        b = lum(img, x + 1, y),
        c = lum(img, x, y + 1);
      worst = Math.max(worst, Math.abs(a - b), Math.abs(a - c));
    }
  }
  return worst;
}

describe('SurfaceLayer', () => {
  gpuTest('draws a lit, two-sided, smooth surface', async ({ gpu }) => {
    const { device } = gpu;
    const dims: Dims = [24, 24, 24];
    const surface = createCpuSurface(device, sphereVolume(24), dims, 11.3); // radius 8.7
    const frameLayout = createFrameBindGroupLayout(device);
    const camera = new ArcballCamera();
    const layer = await SurfaceLayer.create({ device, format: 'rgba8unorm', frameBindGroupLayout: frameLayout, camera });
    layer.setDrawData(surface.data);
    camera.fit({ min: [0, 0, 0], max: [23, 23, 23] });

    const outside = await render(device, layer, camera, frameLayout);
    const centre = px(outside, SIZE / 2, SIZE / 2);
    // Facing the headlight: bright, and the warm outside colour (red > blue).
    expect(centre[0]).toBeGreaterThan(150);
    expect(centre[0]).toBeGreaterThan(centre[2]);
    // The corners are background.
    expect(px(outside, 2, 2)).toEqual([0, 0, 0]);
    const smoothStep = largestStep(outside);

    layer.style.smooth = false;
    const flat = await render(device, layer, camera, frameLayout);
    const flatStep = largestStep(flat);
    // Gradient normals: no facet edges; per-triangle normals: visible steps.
    expect(smoothStep).toBeLessThan(flatStep * 0.5);
    // Seen from outside, flat or smooth: the outside colour.
    expect(px(flat, SIZE / 2, SIZE / 2)[0]).toBeGreaterThan(px(flat, SIZE / 2, SIZE / 2)[2]);
    layer.style.smooth = true;

    // From the centre of the sphere, the inside (back) colour: blue > red.
    camera.setState({ ...camera.getState(), target: [11.5, 11.5, 11.5], distance: 0.5 });
    const inside = await render(device, layer, camera, frameLayout);
    const c2 = px(inside, SIZE / 2, SIZE / 2);
    expect(c2[2]).toBeGreaterThan(c2[0]);
    expect(c2[2]).toBeGreaterThan(60);

    layer.destroy();
    surface.destroy();
  });

  gpuTest('shades from one-sided differences where neighbour blocks are not cached', async ({ gpu }) => {
    const { device } = gpu;
    const dims: Dims = [24, 24, 24];
    const surface = createCpuSurface(device, sphereVolume(24), dims, 11.3);
    const frameLayout = createFrameBindGroupLayout(device);
    const camera = new ArcballCamera();
    const layer = await SurfaceLayer.create({ device, format: 'rgba8unorm', frameBindGroupLayout: frameLayout, camera });
    layer.setDrawData(surface.data);
    camera.fit({ min: [0, 0, 0], max: [23, 23, 23] });
    const full = await render(device, layer, camera, frameLayout);
    // Keep only the blocks holding an end of a vertex's grid edge (what the
    // pipeline always has cached); the gradients' outer neighbours are gone,
    // and the normals (computed once per surface, as the pipeline does) use
    // one-sided differences there.
    const keep = new Set<number>();
    const cell = (x: number, y: number, z: number) => (x >> 2) + 6 * ((y >> 2) + 6 * (z >> 2));
    const soup = marchingCubes(sphereVolume(24), dims, 11.3).positions;
    for (let i = 0; i < soup.length; i += 3) {
      keep.add(cell(Math.floor(soup[i]), Math.floor(soup[i + 1]), Math.floor(soup[i + 2])));
      keep.add(cell(Math.ceil(soup[i]), Math.ceil(soup[i + 1]), Math.ceil(soup[i + 2])));
    }
    const blocks = 6 * 6 * 6;
    expect(keep.size).toBeLessThan(blocks * 0.75);
    const oneSided = createCpuSurface(device, sphereVolume(24), dims, 11.3, (b) => keep.has(b));
    layer.setDrawData(oneSided.data);
    const partial = await render(device, layer, camera, frameLayout);
    oneSided.destroy();
    let covered = 0,
      diff = 0;
    for (let i = 0; i < SIZE * SIZE; i++) {
      const a = full[4 * i] + full[4 * i + 1] + full[4 * i + 2];
      const b = partial[4 * i] + partial[4 * i + 1] + partial[4 * i + 2];
      if (a > 0) {
        covered++;
        diff += Math.abs(a - b);
      }
      // Never NaN-black where the surface is.
      if (a > 0) expect(b).toBeGreaterThan(0);
    }
    expect(covered).toBeGreaterThan(SIZE * SIZE * 0.08);
    // One-sided differences of a smooth field: nearly the same image.
    expect(diff / covered / 3).toBeLessThan(12);
    layer.destroy();
    surface.destroy();
  });

  gpuTest('draws voxel (i, j, k) at (i, j, k) * voxelSize', async ({ gpu }) => {
    const { device } = gpu;
    const dims: Dims = [24, 24, 24];
    const values = sphereVolume(24);
    const surface = createCpuSurface(device, values, dims, 11.3);
    const frameLayout = createFrameBindGroupLayout(device);
    const camera = new ArcballCamera();
    const layer = await SurfaceLayer.create({ device, format: 'rgba8unorm', frameBindGroupLayout: frameLayout, camera });
    layer.setDrawData(surface.data);
    layer.voxelSize = [1, 0.75, 2.5];
    camera.fit({ min: [0, 0, 0], max: [23, 17.25, 57.5] });
    const img = await render(device, layer, camera, frameLayout);
    // The covered pixels' bounding box, against the CPU projection of the scaled soup's vertices.
    const box = (xs: number[], ys: number[]) => [Math.min(...xs), Math.min(...ys), Math.max(...xs), Math.max(...ys)];
    const xs: number[] = [],
      ys: number[] = [];
    for (let y = 0; y < SIZE; y++)
      for (let x = 0; x < SIZE; x++)
        if (lum(img, x, y) > 0) {
          xs.push(x);
          ys.push(y);
        }
    const drawn = box(xs, ys);
    const vp = camera.viewProjection(mat4.create());
    const soup = marchingCubes(values, dims, 11.3).positions;
    const px: number[] = [],
      py: number[] = [];
    for (let i = 0; i < soup.length; i += 3) {
      const c = vec4.transformMat4(vec4.create(), [soup[i], soup[i + 1] * 0.75, soup[i + 2] * 2.5, 1], vp);
      px.push(((c[0] / c[3] + 1) / 2) * SIZE - 0.5);
      py.push(((1 - c[1] / c[3]) / 2) * SIZE - 0.5);
    }
    const expected = box(px, py);
    // An ellipsoid 2.5x taller than wide, not the sphere of the unscaled soup.
    expect(drawn[3] - drawn[1]).toBeGreaterThan(1.8 * (drawn[2] - drawn[0]));
    drawn.forEach((v, i) => expect(Math.abs(v - expected[i])).toBeLessThanOrEqual(1.5));
    layer.destroy();
    surface.destroy();
  });

  gpuTest(
    'pieces (a store refined by the view): each at scale x voxelSize from its origin, as one soup would be drawn',
    async ({ gpu }) => {
      const { device } = gpu;
      const dims: Dims = [24, 24, 24];
      const values = sphereVolume(24);
      const surface = createCpuSurface(device, values, dims, 11.3);
      const frameLayout = createFrameBindGroupLayout(device);
      const camera = new ArcballCamera();
      const layer = await SurfaceLayer.create({ device, format: 'rgba8unorm', frameBindGroupLayout: frameLayout, camera });
      camera.fit({ min: [0, 0, 0], max: [60, 60, 60] });
      const covered = (img: Uint8Array) => {
        const xs: number[] = [];
        const ys: number[] = [];
        for (let y = 0; y < SIZE; y++)
          for (let x = 0; x < SIZE; x++)
            if (lum(img, x, y) > 0) {
              xs.push(x);
              ys.push(y);
            }
        return [Math.min(...xs), Math.min(...ys), Math.max(...xs), Math.max(...ys)];
      };
      // one piece at scale (2, 3, 1) (a level that halves x and thirds y) from origin (3, 1, 0) (in its own voxels), against the soup placed there on the CPU
      layer.setDrawData(surface.data);
      layer.setParts([{ data: surface.data, scale: [2, 3, 1], origin: [3, 1, 0] }]);
      const drawn = covered(await render(device, layer, camera, frameLayout));
      const vp = camera.viewProjection(mat4.create());
      const soup = marchingCubes(values, dims, 11.3).positions;
      const px: number[] = [];
      const py: number[] = [];
      for (let i = 0; i < soup.length; i += 3) {
        const p = [(soup[i] + 3) * 2, (soup[i + 1] + 1) * 3, soup[i + 2]];
        const c = vec4.transformMat4(vec4.create(), [p[0], p[1], p[2], 1], vp);
        px.push(((c[0] / c[3] + 1) / 2) * SIZE - 0.5);
        py.push(((1 - c[1] / c[3]) / 2) * SIZE - 0.5);
      }
      const expected = [Math.min(...px), Math.min(...py), Math.max(...px), Math.max(...py)];
      drawn.forEach((v, i) => expect(Math.abs(v - expected[i])).toBeLessThanOrEqual(1.5));
      // a tint changes the colour, not the coverage; back to the single draw data without parts
      layer.setParts([{ data: surface.data, scale: [2, 3, 1], origin: [3, 1, 0], tint: [0.2, 0.2, 1.5] }]);
      const tinted = await render(device, layer, camera, frameLayout);
      expect(covered(tinted)).toEqual(drawn);
      layer.setParts(undefined);
      const single = covered(await render(device, layer, camera, frameLayout));
      expect(single[2] - single[0]).toBeLessThan(drawn[2] - drawn[0]);
      layer.destroy();
      surface.destroy();
    },
  );

  gpuTest('the depth-only pass writes the depths the lit pass draws at', async ({ gpu }) => {
    const { device } = gpu;
    const dims: Dims = [24, 24, 24];
    const surface = createCpuSurface(device, sphereVolume(24), dims, 11.3);
    const frameLayout = createFrameBindGroupLayout(device);
    const camera = new ArcballCamera();
    const layer = await SurfaceLayer.create(
      { device, format: 'rgba8unorm', frameBindGroupLayout: frameLayout, camera },
      { depthPrepass: true },
    );
    layer.setDrawData(surface.data);
    layer.voxelSize = [0.5, 0.5, 1.5];
    camera.fit({ min: [0, 0, 0], max: [11.5, 11.5, 34.5] });
    expect(layer.hasDepth).toBe(true);
    const covered = (img: Uint8Array) => {
      let n = 0;
      for (let i = 0; i < SIZE * SIZE; i++) if (img[4 * i] + img[4 * i + 1] + img[4 * i + 2] > 0) n++;
      return n;
    };
    expect(covered(await render(device, layer, camera, frameLayout))).toBeGreaterThan(SIZE * SIZE * 0.05);
    // Depth test 'less' against the pre-pass: every fragment ties with what the pre-pass wrote, so none is drawn.
    expect(covered(await render(device, layer, camera, frameLayout, true))).toBe(0);
    layer.visible = false;
    expect(layer.hasDepth).toBe(false);
    layer.destroy();
    surface.destroy();
  });
});
