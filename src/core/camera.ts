// The page camera's math, as pure functions every layer shares: the page's
// ArcballCamera (src/render/camera.ts) draws with it, and the store's view
// cut (src/store/view/camera.ts) plans with it, so the cut sees what the
// page shows. gl-matrix arrays of any precision (the page's float32, the
// cut's float64).
import { mat3, mat4, quat, vec3 } from 'gl-matrix';
import { DEFAULT_VIEW_DIRECTION } from './view.ts';

/** The page's vertical field of view. */
export const FOV_Y_RAD = (40 * Math.PI) / 180;

/** The world axis shown pointing up by a fit: LIDAR and terrain use z, CT and ParaView's default y. */
export type UpAxis = 'x' | 'y' | 'z';

/**
 * A fit's rotation (world to eye) into `out`: y up, from the front (+z),
 * right (+x) and a little above (DEFAULT_VIEW_DIRECTION), like ParaView's
 * default view turned to three-quarters; x up: the same with axes cycled;
 * z up: from -x, -y, a little above.
 */
export function fitRotation<Q extends quat>(out: Q, up: UpAxis): Q {
  if (up === 'z') {
    const q = quat.create();
    quat.setAxisAngle(q, [1, 0, 0], (-62 * Math.PI) / 180);
    const yaw = quat.create();
    quat.setAxisAngle(yaw, [0, 0, 1], (35 * Math.PI) / 180);
    quat.multiply(out, q, yaw);
    return out;
  }
  const d = DEFAULT_VIEW_DIRECTION;
  const dir = up === 'y' ? vec3.fromValues(d[0], d[1], d[2]) : vec3.fromValues(d[2], d[0], d[1]);
  const upVec = up === 'y' ? vec3.fromValues(0, 1, 0) : vec3.fromValues(1, 0, 0);
  const look = mat4.lookAt(mat4.create(), vec3.normalize(dir, dir), [0, 0, 0], upVec);
  quat.fromMat3(out, mat3.fromMat4(mat3.create(), look));
  quat.normalize(out, out);
  return out;
}

/** The distance at which a sphere of `sceneRadius` fits the view, with a margin. */
export function fitDistance(sceneRadius: number, fovYRad = FOV_Y_RAD): number {
  return (sceneRadius / Math.sin(fovYRad / 2)) * 1.05;
}

/** Near and far planes at `distance` from the target, for a scene of `sceneRadius` around it. */
export function nearFar(distance: number, sceneRadius: number): [number, number] {
  return [Math.max(distance - sceneRadius * 1.5, distance * 0.01, 1e-4), distance + sceneRadius * 1.5];
}

/** World to eye: T(0, 0, -distance) * R * T(-target) (eye = R^-1 (0, 0, distance) + target). Allocates nothing (every frame). */
export function viewMatrix<M extends mat4>(out: M, rotation: quat, target: ArrayLike<number>, distance: number): M {
  mat4.fromTranslation(out, vec3.set(scratchV, 0, 0, -distance));
  mat4.multiply(out, out, mat4.fromQuat(scratchM, rotation));
  mat4.translate(out, out, vec3.set(scratchV, -target[0], -target[1], -target[2]));
  return out;
}

const scratchV = new Float64Array(3) as unknown as vec3;
const scratchM = new Float64Array(16) as unknown as mat4;
