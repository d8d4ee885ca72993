// Rays over a store refined where they found the surface (issue 46): the
// image's depth gives each covered pixel's first hit; the level-0 chunks
// there (seen.ts: with a guard along the ray) go to the stream
// (StoreStream.setSeen), which plans a cut for rays (finer chunks only there,
// nested over coarser ones: CutInput.seen) and refines; the scene is made
// again and drawn, until an image's rays hit no chunk not asked for yet, or
// MAX_GUIDED_PASSES. What `render` and `bench:rays` do after the view's cut.
import { mat4, vec4 } from 'gl-matrix';
import type { IsosurfaceStats } from '../isosurface/types.ts';
import type { ArcballCamera } from '../render/camera.ts';
import type { StoreStreamSurface } from '../store/stream-surface.ts';
import { regionOwners } from '../store/view/regions.ts';
import { seenChunks } from '../store/view/seen.ts';
import { InputError } from './command.ts';
import { destroyScene, type Layer, type Scene } from './scene.ts';

/** How many times at most a store's rays are refined again where they found the surface (each an image more). */
export const MAX_GUIDED_PASSES = 4;

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
  let seen: Uint8Array | undefined;
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
  const seenCount = seen ? seen.reduce((a, b) => a + b, 0) : 0;
  return { scene, image, passes, seenChunks: seenCount, ms: performance.now() - t0 };
}

/** Each covered pixel's first hit in level-0 voxels (x, y, z) and its ray's unit direction there, from an image's depth. */
export function hitsOf(
  depth: Float32Array,
  camera: ArcballCamera,
  [width, height]: readonly [number, number],
  voxelSize: readonly number[],
  origin: readonly number[],
): { hits: Float64Array; dirs: Float64Array } {
  camera.aspect = width / height;
  const inverse = mat4.invert(mat4.create(), camera.viewProjection(mat4.create()));
  if (!inverse) return { hits: new Float64Array(0), dirs: new Float64Array(0) };
  const eye = camera.eyePosition();
  const e = [0, 1, 2].map((a) => eye[a] / voxelSize[a] - origin[a]);
  let covered = 0;
  for (let i = 0; i < depth.length; i++) if (depth[i] < 1) covered++;
  const hits = new Float64Array(3 * covered);
  const dirs = new Float64Array(3 * covered);
  const p = vec4.create();
  let k = 0;
  for (let y = 0; y < height; y++)
    for (let x = 0; x < width; x++) {
      const z = depth[y * width + x];
      if (!(z < 1)) continue;
      vec4.transformMat4(p, [((x + 0.5) / width) * 2 - 1, 1 - ((y + 0.5) / height) * 2, z, 1], inverse);
      let len = 0;
      for (let a = 0; a < 3; a++) {
        hits[k + a] = p[a] / p[3] / voxelSize[a] - origin[a];
        dirs[k + a] = hits[k + a] - e[a];
        len += dirs[k + a] * dirs[k + a];
      }
      len = Math.sqrt(len) || 1;
      for (let a = 0; a < 3; a++) dirs[k + a] /= len;
      k += 3;
    }
  return { hits, dirs };
}

/** The store's surface refined where the rays found it, or the stream's reason it stopped, as an input error. */
async function guideOrExplain(surface: StoreStreamSurface, seen: Uint8Array): Promise<IsosurfaceStats> {
  try {
    return await surface.guide(seen);
  } catch (e) {
    if ((e as Error).name === 'LevelStoppedError') throw new InputError((e as Error).message, { cause: e });
    throw e;
  }
}
