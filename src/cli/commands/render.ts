// `render IN --iso v --png OUT.png [--draw rays|mesh] [--size WxH]
// [--view '#cam=..' | --view-box x0,y0,z0,x1,y1,z1] [--cache-budget MB]
// [--depth OUT.f32] [--json REC]`: a figure without a browser, drawn by the
// page's own layers on Dawn: the surface ray cast in the block cache
// (render/ray-layer.ts; the default) or its triangles (surface-layer.ts),
// lit as in the page, on the page's background. --depth writes each pixel's
// hit distance from the eye along its ray, in level-0 voxels (float32, rows
// top to bottom; +Infinity where nothing was hit). IN: a volume opened
// whole, or a Zarr store refined by the image's view (its cut for that
// camera and size, as the page's): every level of the step drawn, and the
// record says which level each covered pixel's hit lies in (level0Fraction;
// --level-map writes it per pixel, a byte each, 255 where nothing was hit).
import { writeFileSync } from 'node:fs';
import { mat4, vec4 } from 'gl-matrix';
import { describeAdapter } from '../../gpu/device.ts';
import { meteredGpu } from '../../gpu/memory-meter.ts';
import type { Isosurface } from '../../isosurface/isosurface.ts';
import type { IsosurfaceStats } from '../../isosurface/types.ts';
import { ArcballCamera } from '../../render/camera.ts';
import { renderOffscreen } from '../../render/offscreen.ts';
import { createFrameBindGroupLayout } from '../../render/viewer.ts';
import { isStoreInput } from '../../store/cli-input.ts';
import type { StoreStreamSurface } from '../../store/stream-surface.ts';
import { cameraForBox, fitBox0, parseCam } from '../../store/view/camera.ts';
import { parseViewBox, type ViewRequest } from '../../store/view/view-request.ts';
import { type CliCommand, InputError, numberOption, requiredPositional, stringOption, UsageError } from '../command.ts';
import { openInputSurface } from '../input.ts';
import { encodePng } from '../png.ts';
import { type Guided, guideRays } from '../guide-rays.ts';
import { destroyScene, fitWhole, levelPerPixel, type Scene, storeScene, wholeScene } from '../scene.ts';
import { budgetOption } from './extract.ts';

/** The page's background (render/viewer.ts's default clear colour). */
const MAX_SIDE = 8192;

export const renderCommand: CliCommand = {
  name: 'render',
  summary: "an image of the surface (ray cast in the block cache, or its triangles) as PNG, with each pixel's hit distance",
  usage:
    "render IN --iso v --png OUT.png [--draw rays|mesh] [--size WxH] [--view '#cam=..' | --view-box x0,y0,z0,x1,y1,z1] [--tolerance PX] [--mesh-cut] [--no-guide] [--rate R] [--cache-budget MB] [--time T] [--channel C] [--depth OUT.f32] [--level-map OUT.u8] (IN: a volume opened whole, as extract's, or a Zarr store refined by the image's view; rays by default, over surfaces of block caches only, so a store's cut spends the budget on bricks; --mesh-cut: rays over the cut the mesh path makes, surfaces with triangles, to compare the two on one cut; a store's rays are refined again where they found the surface, up to 4 images more, unless --no-guide)",
  options: {
    iso: { type: 'string' },
    png: { type: 'string' },
    draw: { type: 'string' },
    size: { type: 'string' },
    view: { type: 'string' },
    'view-box': { type: 'string' },
    tolerance: { type: 'string' },
    'mesh-cut': { type: 'boolean' },
    'no-guide': { type: 'boolean' },
    rate: { type: 'string' },
    'cache-budget': { type: 'string' },
    time: { type: 'string' },
    channel: { type: 'string' },
    depth: { type: 'string' },
    'level-map': { type: 'string' },
  },
  async run(ctx, args) {
    const input = requiredPositional(args, 0, 'IN (a zfp file, a raw volume or a Zarr store)');
    const iso = numberOption(args, 'iso');
    if (iso === undefined) throw new UsageError('give the isovalue with --iso v');
    const pngPath = stringOption(args, 'png');
    if (!pngPath) throw new UsageError('give the image file with --png OUT.png');
    const draw = stringOption(args, 'draw') ?? 'rays';
    if (draw !== 'rays' && draw !== 'mesh') throw new UsageError(`--draw ${draw}: rays or mesh`);
    const [width, height] = sizeOption(stringOption(args, 'size') ?? '1280x720');
    const viewBox = stringOption(args, 'view-box');
    const view = stringOption(args, 'view');
    if (viewBox !== undefined && view !== undefined) throw new UsageError('give --view-box or --view, not both');
    const box = viewBox === undefined ? undefined : parseViewBox(viewBox);
    if (typeof box === 'string') throw new UsageError(`--view-box ${viewBox}: ${box}`);
    const cam = view === undefined ? undefined : parseCam(new URLSearchParams(view.replace(/^.*#/, '')).get('cam') ?? '');
    if (cam === null) throw new UsageError(`--view ${view}: the page's link, with its camera (#cam=qx,qy,qz,qw,tx,ty,tz,d)`);
    const tolerancePx = numberOption(args, 'tolerance');
    if (tolerancePx !== undefined && !(tolerancePx > 0)) throw new UsageError('--tolerance must be a positive number of pixels');
    const store = isStoreInput(input);
    const meshCut = args.values['mesh-cut'] === true;
    if (!store && tolerancePx !== undefined) throw new UsageError('--tolerance is for a Zarr store (the view refines it)');
    // a store is refined by the image's own view: its camera on a canvas of the image's size
    const viewRequest: ViewRequest | undefined = store
      ? { ...(box ? { box } : view !== undefined ? { link: view } : { whole: true }), viewport: { width, height }, tolerancePx }
      : undefined;
    const device = await ctx.gpu();
    const { gpu, meter } = meteredGpu(device);
    const opened = await openInputSurface(ctx, gpu, input, {
      rate: numberOption(args, 'rate'),
      budget: storeBudget(budgetOption(args), store, width, height),
      // rays read the block caches only: no triangles, no vertex memory (unless asked for the mesh path's cut)
      cacheOnly: draw === 'rays' && !meshCut,
      ...(store ? { view: viewRequest, time: numberOption(args, 'time'), channel: numberOption(args, 'channel') } : {}),
    });
    let scene: Scene | undefined;
    try {
      const { voxelSize, origin } = opened.placement;
      const camera = new ArcballCamera();
      const frameLayout = createFrameBindGroupLayout(gpu.device);
      const target = { device: gpu.device, format: 'rgba8unorm' as GPUTextureFormat, frameBindGroupLayout: frameLayout, camera };
      const world = (v: readonly number[]) => v.map((x, a) => (x + origin[a]) * voxelSize[a]) as [number, number, number];
      const t0 = performance.now();
      if ('readPositions' in opened.iso) {
        const surface = opened.iso as StoreStreamSurface;
        const stats = await computeOrExplain(surface, iso);
        // the page's scene of a store (level 0's box: near and far), and the camera the cut was made for
        // (viewSpecFor(viewRequest): Fit of the box or of the whole, or the link's, on this canvas)
        const whole = fitBox0(surface.stream.store.levels[0].layout, 0);
        camera.fit({ min: world(whole.slice(0, 3)), max: world(whole.slice(3, 6)) }, 'y');
        camera.setState(cam ?? cameraForBox(box ?? whole, voxelSize, { width, height }).state);
        scene = await storeScene(target, surface, stats, draw, voxelSize, origin);
      } else {
        const surface = opened.iso as Isosurface;
        const stats = await surface.compute(iso);
        // the page's camera: fitted to the volume (or the box), or the link's; world = (voxel + origin) * voxel size
        const { dims } = surface.info;
        fitWhole(camera, dims, voxelSize, origin, box);
        if (cam) camera.setState(cam);
        scene = await wholeScene(target, surface, stats, draw, voxelSize, origin);
      }
      const surfaceMs = performance.now() - t0;
      let image = await renderOffscreen(gpu.device, frameLayout, camera, width, height, scene.layer);
      // rays over a store: refined again where the image's rays found the surface, until they find it in no
      // chunk not asked for yet (a cut for rays: finer bricks only there, nested over coarser ones)
      let guided: Guided | undefined;
      if (draw === 'rays' && !meshCut && args.values['no-guide'] !== true && 'readPositions' in opened.iso) {
        const surface = opened.iso as StoreStreamSurface;
        const g = await guideRays(
          surface,
          scene,
          image,
          camera,
          [width, height],
          voxelSize,
          origin,
          (stats) => storeScene(target, surface, stats, draw, voxelSize, origin),
          (layer) => renderOffscreen(gpu.device, frameLayout, camera, width, height, layer),
          (s) => {
            scene = s;
          },
        );
        scene = g.scene;
        image = g.image;
        guided = { passes: g.passes, seenChunks: g.seenChunks, ms: g.ms };
      }
      const { stats } = scene;
      writeFileSync(pngPath, encodePng(image.colour, width, height));
      // which level each covered pixel shows
      const pixelLevel = await levelPerPixel(
        scene,
        image.depth,
        async (layer) => (await renderOffscreen(gpu.device, frameLayout, camera, width, height, layer)).depth,
      );
      // each pixel's hit distance from the eye, in level-0 voxels (world / voxel size), along its ray
      camera.aspect = width / height;
      const inverse = mat4.invert(mat4.create(), camera.viewProjection(mat4.create()));
      const eye = camera.eyePosition();
      const distances = new Float32Array(width * height);
      let covered = 0;
      const pixelsPerLevel = new Map<number, number>();
      const p = vec4.create();
      for (let y = 0; y < height; y++) {
        for (let x = 0; x < width; x++) {
          const i = y * width + x;
          const z = image.depth[i];
          if (!(z < 1) || !inverse) {
            distances[i] = Number.POSITIVE_INFINITY;
            continue;
          }
          covered++;
          if (pixelLevel[i] >= 0) pixelsPerLevel.set(pixelLevel[i], (pixelsPerLevel.get(pixelLevel[i]) ?? 0) + 1);
          vec4.transformMat4(p, [((x + 0.5) / width) * 2 - 1, 1 - ((y + 0.5) / height) * 2, z, 1], inverse);
          distances[i] = Math.hypot(
            (p[0] / p[3] - eye[0]) / voxelSize[0],
            (p[1] / p[3] - eye[1]) / voxelSize[1],
            (p[2] / p[3] - eye[2]) / voxelSize[2],
          );
        }
      }
      const depthPath = stringOption(args, 'depth');
      if (depthPath) writeFileSync(depthPath, new Uint8Array(distances.buffer));
      // each pixel's level (rows top to bottom; 255 where nothing was hit)
      const levelMapPath = stringOption(args, 'level-map');
      if (levelMapPath)
        writeFileSync(
          levelMapPath,
          Uint8Array.from(pixelLevel, (L) => (L < 0 ? 255 : L)),
        );
      const level0 = pixelsPerLevel.get(0) ?? 0;
      ctx.log(
        `${pngPath}: ${width} x ${height}, ${draw === 'rays' ? 'ray cast in the block cache' : `${stats.triangles} triangles`}, ${covered} pixels on the surface` +
          `${scene.levels.length > 0 ? ` (${covered > 0 ? ((100 * level0) / covered).toFixed(1) : '0'}% from level 0)` : ''}, image ${image.ms.toFixed(1)} ms (${image.timing})`,
      );
      return {
        input,
        how: opened.how,
        rate: opened.rate,
        iso: stats.isovalue,
        draw,
        size: [width, height],
        camera: camera.getState(),
        // the pixels' rays, for checking the depths elsewhere: ndc (x, y, z in [0, 1]) -> world by this matrix (column-major)
        inverseViewProjection: inverse ? [...inverse] : null,
        eye: [...eye],
        png: pngPath,
        ...(depthPath ? { depth: depthPath } : {}),
        ...(levelMapPath ? { levelMap: levelMapPath } : {}),
        coveredPixels: covered,
        // a volume opened whole is level 0 everywhere
        levels: scene.levels.length > 0 ? scene.levels.map((l) => l.level) : [0],
        ...(scene.levels.length > 0 ? { cut: scene.levels } : {}),
        pixelsPerLevel: Object.fromEntries([...pixelsPerLevel].sort((a, b) => a[0] - b[0])),
        level0Fraction: covered > 0 ? level0 / covered : 0,
        activeBlocks: stats.activeBlocks,
        triangles: draw === 'mesh' ? stats.triangles : 0,
        surfaceMs,
        surfaceGpuMs: stats.gpuMs,
        // rays over a store: the passes refined where the rays found the surface, level-0 chunks seen, their time (surfaces and images)
        ...(guided ? { guided } : {}),
        imageMs: image.ms,
        imageTiming: image.timing,
        gpuPeakBytes: meter.peak,
        ...(opened.store ? { store: opened.store() } : {}),
        adapter: describeAdapter(gpu.adapter),
      };
    } finally {
      destroyScene(scene);
      opened.destroy();
    }
  },
};

/**
 * A store's stream holds what the budget leaves beside the image's read-back
 * (colour and depth, each row padded to 256 bytes: 7 MiB at 1280x720), so
 * that the run's GPU peak stays within the budget.
 */
function storeBudget(budget: number | undefined, store: boolean, width: number, height: number): number | undefined {
  if (budget === undefined || !store) return budget;
  const readBack = 2 * 256 * Math.ceil((4 * width) / 256) * height;
  if (budget <= 2 * readBack)
    throw new UsageError(
      `--cache-budget: ${(budget / 2 ** 20).toFixed(1)} MB leaves no room beside the image's read-back (${(readBack / 2 ** 20).toFixed(1)} MB at ${width}x${height})`,
    );
  return budget - readBack;
}

/** The store's surface at `iso`, or the stream's reason it stopped (a failed chunk, the budget) as an input error. */
async function computeOrExplain(surface: StoreStreamSurface, iso: number): Promise<IsosurfaceStats> {
  try {
    return await surface.compute(iso);
  } catch (e) {
    if ((e as Error).name === 'LevelStoppedError') throw new InputError((e as Error).message, { cause: e });
    throw e;
  }
}

/** --size WxH -> [width, height] (render, bench --draw). */
export function sizeOption(text: string): [number, number] {
  const m = /^(\d+)x(\d+)$/.exec(text);
  const w = m ? Number(m[1]) : Number.NaN;
  const h = m ? Number(m[2]) : Number.NaN;
  if (!(w >= 1 && h >= 1 && w <= MAX_SIDE && h <= MAX_SIDE)) throw new UsageError(`--size ${text}: WxH, each 1..${MAX_SIDE}`);
  return [w, h];
}
