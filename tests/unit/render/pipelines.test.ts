// Every page's render layer creates its shader module and pipelines without a
// WebGPU error: the surface (main page), its ray caster, the caps, the box, the clip handles, LIDAR points, the neuron
// page's volume ray marcher and SWC tubes. The drawing itself is checked by
// surface-layer.test.ts and the page tests; this file matters most in the
// `wgpu` suite (scripts/test-wgpu.mjs), where naga, Firefox's shader
// compiler, sees the render shaders that only Chromium (Dawn) runs otherwise.
import { describe, expect } from 'vitest';
import { PointLayer } from '../../../src/examples/lidar/point-layer.ts';
import { DepthPrepass } from '../../../src/examples/neuron/depth-prepass.ts';
import { SwcLayer } from '../../../src/examples/neuron/swc-layer.ts';
import { VolumeLayer } from '../../../src/examples/neuron/volume-layer.ts';
import { BoxLayer } from '../../../src/render/box-layer.ts';
import { ArcballCamera } from '../../../src/render/camera.ts';
import { CapLayer } from '../../../src/render/cap-layer.ts';
import { ClipHandleLayer } from '../../../src/render/clip-handles.ts';
import { RayLayer } from '../../../src/render/ray-layer.ts';
import { SurfaceLayer } from '../../../src/render/surface-layer.ts';
import { createFrameBindGroupLayout, type Viewer } from '../../../src/render/viewer.ts';
import { gpuTest } from '../../helpers/gpu.ts';

/** The parts of a Viewer the layers use at creation, with no canvas. */
function offscreenViewer(device: GPUDevice): Viewer {
  const beforeFrame: unknown[] = [];
  const fake = {
    device,
    format: 'rgba8unorm' as GPUTextureFormat,
    frameBindGroupLayout: createFrameBindGroupLayout(device),
    camera: new ArcballCamera(),
    canvas: { width: 64, height: 48 },
    requestFrame: () => undefined,
    addBeforeFrame: (f: unknown) => {
      beforeFrame.push(f);
      return () => undefined;
    },
  };
  return fake as unknown as Viewer;
}

describe('render pipelines compile', () => {
  gpuTest('surface, ray caster, caps, box, clip handles, points, volume ray marcher, SWC tubes', async ({ gpu }) => {
    const viewer = offscreenViewer(gpu.device);
    const layers = [
      await SurfaceLayer.create(viewer),
      await RayLayer.create(viewer),
      await CapLayer.create(viewer),
      await BoxLayer.create(viewer),
      await ClipHandleLayer.create(viewer),
      await PointLayer.create(viewer),
      await SwcLayer.create(viewer),
      await VolumeLayer.create(viewer, new DepthPrepass(viewer)),
    ];
    expect(layers.length).toBe(8);
  });
});
