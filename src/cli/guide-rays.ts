// Rays over a store refined where they found the surface (issue 46): the
// image's depth gives each covered pixel's first hit; the level-0 chunks
// there (seen.ts: with a guard along the ray) go to the stream
// (StoreStream.setSeen), which plans a cut for rays (finer chunks only there,
// nested over coarser ones: CutInput.seen) and refines; the scene is made
// again and drawn, until an image's rays hit no chunk not asked for yet, or
// MAX_GUIDED_PASSES. What `render` and `bench:rays` do after the view's cut.
import { mat4 } from 'gl-matrix';
import type { IsosurfaceStats } from '../isosurface/types.ts';
import type { ArcballCamera } from '../render/camera.ts';
import type { StoreStreamSurface } from '../store/stream-surface.ts';
import { regionOwners } from '../store/view/regions.ts';
import { hitsFromDepth, MAX_GUIDED_PASSES, seenChunks } from '../store/view/seen.ts';
import { InputError } from './command.ts';
import { destroyScene, type Layer, type Scene } from './scene.ts';

/** What the guided passes did: how many, the level-0 chunks seen in all, their time (surfaces and images), ms. */
export interface Guided {
  passes: number;
  seenChunks: number;
  ms: number;
}

/**
 * Refines `surface` where the rays of `image` (drawn from `scene` by
 * `camera` at `size`) found it, again and again; `makeScene` makes the scene
 * of the step then shown, `draw` draws a layer. The old scene is destroyed
 * (`replaced` hears of each new one first, so a caller that throws keeps
 * none alive). Returns the last scene and image.
 */
export async function guideRays<I extends { depth: Float32Array }>(
  surface: StoreStreamSurface,
  scene: Scene,
  image: I,
  camera: ArcballCamera,
  size: readonly [number, number],
  voxelSize: readonly number[],
  origin: readonly number[],
  makeScene: (stats: IsosurfaceStats) => Promise<Scene>,
  draw: (layer: Layer) => Promise<I>,
  replaced: (scene: Scene | undefined) => void,
): Promise<Guided & { scene: Scene; image: I }> {
  const { stream } = surface;
  const level0 = stream.levels[0].layout;
  const t0 = performance.now();
  let seen: Uint32Array | undefined;
  let passes = 0;
  for (let pass = 0; pass < MAX_GUIDED_PASSES; pass++) {
    const shown = stream.shown!;
    const regions = regionOwners(
      shown.leaves,
      stream.levels.map((l) => l.layout),
      stream.store.levelScales,
    );
    const { hits, dirs } = hitsOf(image.depth, camera, size, voxelSize, origin);
    const next = seenChunks(hits, dirs, level0, regions, stream.store.levelScales, seen);
    seen = next.seen;
    if (next.added === 0) break;
    const stats = await guideOrExplain(surface, seen);
    destroyScene(scene);
    replaced(undefined);
    scene = await makeScene(stats);
    replaced(scene);
    image = await draw(scene.layer);
    passes++;
  }
  const seenCount = seen ? seen.reduce((a, b) => a + (b > 0 ? 1 : 0), 0) : 0;
  return { scene, image, passes, seenChunks: seenCount, ms: performance.now() - t0 };
}

/** Each covered pixel's first hit in level-0 voxels and its ray's direction, from an image's depth seen by `camera`. */
function hitsOf(
  depth: Float32Array,
  camera: ArcballCamera,
  size: readonly [number, number],
  voxelSize: readonly number[],
  origin: readonly number[],
): { hits: Float64Array; dirs: Float64Array } {
  camera.aspect = size[0] / size[1];
  const inverse = mat4.invert(mat4.create(), camera.viewProjection(mat4.create()));
  if (!inverse) return { hits: new Float64Array(0), dirs: new Float64Array(0) };
  return hitsFromDepth(depth, size, inverse, camera.eyePosition(), voxelSize, origin);
}

/** The store's surface refined where the rays found it, or the stream's reason it stopped, as an input error. */
async function guideOrExplain(surface: StoreStreamSurface, seen: Uint32Array): Promise<IsosurfaceStats> {
  try {
    return await surface.guide(seen);
  } catch (e) {
    if ((e as Error).name === 'LevelStoppedError') throw new InputError((e as Error).message, { cause: e });
    throw e;
  }
}
