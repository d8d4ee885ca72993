// What `render` (and `bench:rays`) draw: a volume opened whole as one
// layer, or a store's step on screen as one layer of all its levels plus one
// per level alone (which level each pixel shows: the one whose own image is
// nearest there, what the depth test kept), by rays over each level's pool
// and cache (render/ray-layer.ts) or by its triangles (surface-layer.ts).
import type { Isosurface } from '../isosurface/isosurface.ts';
import type { IsosurfaceStats } from '../isosurface/types.ts';
import type { ArcballCamera } from '../render/camera.ts';
import { RayLayer, rayLevelsOf } from '../render/ray-layer.ts';
import { SurfaceLayer, type SurfacePart } from '../render/surface-layer.ts';
import type { RenderLayer } from '../render/viewer.ts';
import type { StoreStreamSurface } from '../store/stream-surface.ts';
import { regionOwners } from '../store/view/regions.ts';

export type Layer = RenderLayer & { destroy(): void };

/** What one run draws: the layer of everything, and per level of a store's step the layer of that level alone (which level each pixel shows). */
export interface Scene {
  layer: Layer;
  levelLayers: { level: number; layer: Layer }[];
  stats: IsosurfaceStats;
  /** A store's step: per level, the chunks drawn and their ghosts. */
  levels: { level: number; drawnChunks: number; ghostChunks: number; triangles: number }[];
}

export type Target = Parameters<typeof RayLayer.create>[0];

/** A volume opened whole: one layer, level 0 everywhere. */
export async function wholeScene(
  target: Target,
  surface: Isosurface,
  stats: IsosurfaceStats,
  draw: 'rays' | 'mesh',
  voxelSize: [number, number, number],
  origin: [number, number, number],
): Promise<Scene> {
  let layer: Layer;
  if (draw === 'rays') {
    const rays = await RayLayer.create(target);
    rays.setDrawData(surface.drawData);
    rays.iso = stats.isovalue;
    rays.voxelSize = [...voxelSize];
    rays.origin = [...origin];
    layer = rays;
  } else {
    const mesh = await SurfaceLayer.create(target);
    mesh.setDrawData(surface.drawData);
    mesh.voxelSize = [...voxelSize];
    mesh.origin = [...origin];
    layer = mesh;
  }
  return { layer, levelLayers: [{ level: 0, layer }], stats, levels: [] };
}

/**
 * The same scene of a volume opened whole at the surface's newer isovalue
 * (computed since on the same pipeline): the rays read the cache at it, the
 * triangles are the drawn data's own. A benchmark draws one image per
 * isovalue without making the layer's pipelines again.
 */
export function wholeSceneAt(scene: Scene, stats: IsosurfaceStats): void {
  scene.stats = stats;
  if (scene.layer instanceof RayLayer) scene.layer.iso = stats.isovalue;
}

/**
 * The page's view of a volume opened whole (Fit, y up) on `camera`: fitted to
 * the voxel box [min, max] (default the whole volume, `dims`), where voxel
 * (i, j, k) lies at ((i, j, k) + origin) * voxelSize.
 */
export function fitWhole(
  camera: ArcballCamera,
  dims: readonly number[],
  voxelSize: readonly number[],
  origin: readonly number[],
  box?: readonly number[],
): void {
  const world = (v: readonly number[]) => v.map((x, a) => (x + origin[a]) * voxelSize[a]) as [number, number, number];
  camera.fit({ min: world(box ? box.slice(0, 3) : [0, 0, 0]), max: world(box ? box.slice(3, 6) : dims.map((n) => n - 1)) }, 'y');
}

/** A store's step on screen: every level at its scale and offset, from its live surface (the CLI's stream draws no copies). */
export async function storeScene(
  target: Target,
  surface: StoreStreamSurface,
  stats: IsosurfaceStats,
  draw: 'rays' | 'mesh',
  voxelSize: [number, number, number],
  origin: [number, number, number],
): Promise<Scene> {
  const { stream } = surface;
  const shown = stream.shown!;
  const { levelOffsets, levelScales } = stream.store;
  const dims = stream.levels[0].layout.dims;
  const placed = shown.levels.map((l) => ({ l, scale: levelScales[l.level], offset: levelOffsets[l.level] }));
  // which level draws each region (a cut for rays keeps coarse chunks drawn under finer ones)
  const regions = regionOwners(
    shown.leaves,
    stream.levels.map((l) => l.layout),
    levelScales,
  ) ?? { grid: [0, 0, 0] as [number, number, number], edge: [1, 1, 1] as [number, number, number], owner: new Uint8Array(0) };
  const make = async (which: typeof placed): Promise<Layer> => {
    if (draw === 'rays') {
      const rays = await RayLayer.create(target);
      // the reach toward the step's coarsest level, also when one level is drawn alone
      const levels = rayLevelsOf(shown.levels, levelScales, levelOffsets).filter((_, i) => which.some((w) => w.l === shown.levels[i]));
      rays.setLevels(levels, dims, regions);
      rays.iso = stats.isovalue;
      rays.voxelSize = [...voxelSize];
      rays.origin = [...origin];
      return rays;
    }
    const mesh = await SurfaceLayer.create(target);
    const parts: SurfacePart[] = which.map(({ scale, offset, l }) => ({
      data: l.surface.drawData,
      scale,
      origin: [(offset[0] + origin[0]) / scale[0], (offset[1] + origin[1]) / scale[1], (offset[2] + origin[2]) / scale[2]],
    }));
    mesh.setParts(parts);
    mesh.voxelSize = [...voxelSize];
    return mesh;
  };
  const layer = await make(placed);
  const levelLayers =
    placed.length === 1
      ? [{ level: placed[0].l.level, layer }]
      : await Promise.all(placed.map(async (p) => ({ level: p.l.level, layer: await make([p]) })));
  return {
    layer,
    levelLayers,
    stats,
    levels: shown.levels.map((l) => ({
      level: l.level,
      drawnChunks: l.drawn.length,
      ghostChunks: l.ghosts.length,
      triangles: l.stats.triangles,
    })),
  };
}

/**
 * Which level each pixel of a frame shows (-1: nothing): the scene's only
 * level, or the level whose own image is nearest there. `render(layer)`
 * draws one frame of a layer and returns its depth.
 */
export async function levelPerPixel(
  scene: Scene,
  depth: Float32Array,
  render: (layer: RenderLayer) => Promise<Float32Array>,
): Promise<Int8Array> {
  const pixelLevel = new Int8Array(depth.length).fill(-1);
  if (scene.levelLayers.length === 1) {
    for (let i = 0; i < pixelLevel.length; i++) if (depth[i] < 1) pixelLevel[i] = scene.levelLayers[0].level;
    return pixelLevel;
  }
  const nearest = new Float32Array(depth.length).fill(1);
  for (const { level, layer } of scene.levelLayers) {
    const solo = await render(layer);
    for (let i = 0; i < nearest.length; i++) {
      if (solo[i] < nearest[i]) {
        nearest[i] = solo[i];
        pixelLevel[i] = level;
      }
    }
  }
  return pixelLevel;
}

/** Destroys a scene's layers. */
export function destroyScene(scene: Scene | undefined): void {
  scene?.layer.destroy();
  for (const l of scene?.levelLayers ?? []) if (l.layer !== scene?.layer) l.layer.destroy();
}
