// The page's camera for the store's view cut, in float64, from the same
// math the page draws with (src/core/camera.ts): its Fit of a box, its state
// -> matrices and eye, the link's cam=. Checked against src/render/camera.ts's
// ArcballCamera in tests/unit/store/view-cut.test.ts.
import { mat4, quat, vec3 } from 'gl-matrix';
import { FOV_Y_RAD, fitDistance, fitRotation, nearFar, type UpAxis, viewMatrix } from '../../core/camera.ts';
import type { CutCamera, CutLevel } from './cut.ts';

/** The page's vertical field of view (src/core/camera.ts). */
export const PAGE_FOV_Y_RAD = FOV_Y_RAD;

export type { UpAxis };

/** The page's camera state, as src/render/camera.ts's CameraState and the link's cam=qx,qy,qz,qw,tx,ty,tz,d. */
export interface ViewCameraState {
  /** Rotation from world to eye orientation, [x, y, z, w]. */
  rotation: [number, number, number, number];
  /** The point the camera orbits, in world units. */
  target: [number, number, number];
  /** From the target to the eye, in world units. */
  distance: number;
}

/** A viewport in device pixels (the canvas' width and height). */
export interface Viewport {
  width: number;
  height: number;
}

/** A box in level-0 voxel coordinates: [x0, y0, z0, x1, y1, z1] (world = these * voxelSize). */
export type Box0 = [number, number, number, number, number, number];

/** A CutCamera with the page camera it stands for. */
export interface ViewCamera extends CutCamera {
  /** The page's camera state (what the link's cam= holds). */
  state: ViewCameraState;
  target: [number, number, number];
  /** The eye's up direction in world units (unit length). */
  up: [number, number, number];
  fovYRad: number;
  /** The page's near and far planes (they follow sceneRadius). */
  near: number;
  far: number;
  /** Half the diagonal of the box the page last fitted: near and far follow it. */
  sceneRadius: number;
  viewport: Viewport;
  /** World -> eye. */
  view: Float64Array;
  /** Eye -> clip. */
  projection: Float64Array;
}

/**
 * The level-0 voxel box the page fits when it shows level `index` of a store:
 * min 0, max (dims_L - 1) * 2^L (the page's bounds (dims_L - 1) * spacing_L
 * with spacing_L = voxelSize * 2^L). For a single volume, index 0.
 */
export function fitBox0(level: Pick<CutLevel, 'dims'>, index: number): Box0 {
  const f = 2 ** index;
  return [0, 0, 0, (level.dims[0] - 1) * f, (level.dims[1] - 1) * f, (level.dims[2] - 1) * f];
}

/** The page's sceneRadius for a fitted box: half its world diagonal (at least 1e-6), in float32 as the page computes it. */
export function sceneRadiusOf(box0: Box0, voxelSize: [number, number, number]): number {
  const [sx, sy, sz] = voxelSize;
  const r =
    0.5 *
    vec3.distance(vec3.fromValues(box0[0] * sx, box0[1] * sy, box0[2] * sz), vec3.fromValues(box0[3] * sx, box0[4] * sy, box0[5] * sz));
  return Math.max(r, 1e-6);
}

/**
 * The camera the page's Fit gives a box: ArcballCamera.fit(bounds, up) with
 * bounds = box0 * voxelSize: it looks at the box centre from the up axis'
 * three-quarter direction (y up, the page's default: from +z, right and a
 * little above, DEFAULT_VIEW_DIRECTION; z up: from -x, -y, above), at
 * distance 1.05 r / sin(fovY / 2) (r = half the box diagonal), near and far
 * from r. Pass fitBox0(level, L) to get the page's view of level L.
 */
export function cameraForBox(
  box0: Box0,
  voxelSize: [number, number, number],
  viewport: Viewport,
  fovYRad = PAGE_FOV_Y_RAD,
  up: UpAxis = 'y',
): ViewCamera {
  const [sx, sy, sz] = voxelSize;
  // the page's target is a float32 vec3
  const t = vec3.fromValues(((box0[0] + box0[3]) * sx) / 2, ((box0[1] + box0[4]) * sy) / 2, ((box0[2] + box0[5]) * sz) / 2);
  const sceneRadius = sceneRadiusOf(box0, voxelSize);
  // in float32 like the page's
  const q = fitRotation(quat.create(), up);
  const state: ViewCameraState = {
    rotation: [q[0], q[1], q[2], q[3]],
    target: [t[0], t[1], t[2]],
    distance: fitDistance(sceneRadius, fovYRad),
  };
  return cameraFromView(state, viewport, sceneRadius, fovYRad);
}

/**
 * The CutCamera of the page's camera state (ArcballCamera.getState(), or the
 * link's cam= through parseCam) on a viewport: the same view, projection
 * (near/far from `sceneRadius`: sceneRadiusOf(fitBox0(shown level...))) and
 * eye as the page's, in float64.
 */
export function cameraFromView(state: ViewCameraState, viewport: Viewport, sceneRadius: number, fovYRad = PAGE_FOV_Y_RAD): ViewCamera {
  const d = state.distance;
  const q = quat.normalize(new Float64Array(4), Float64Array.from(state.rotation));
  const [tx, ty, tz] = state.target;
  const view = viewMatrix(new Float64Array(16), q, state.target, d);
  const [near, far] = nearFar(d, sceneRadius);
  const projection = new Float64Array(16);
  mat4.perspectiveZO(projection, fovYRad, viewport.width / viewport.height, near, far);
  const viewProj = mat4.multiply(new Float64Array(16), projection, view) as Float64Array;
  const inv = quat.invert(new Float64Array(4), q);
  const eye = vec3.transformQuat(new Float64Array(3), [0, 0, d], inv);
  const up = vec3.transformQuat(new Float64Array(3), [0, 1, 0], inv);
  return {
    viewProj,
    eye: [eye[0] + tx, eye[1] + ty, eye[2] + tz],
    pixelsPerUnit: viewport.height / (2 * Math.tan(fovYRad / 2)),
    focus: { point: [tx, ty, tz], radius: 0.5 * d * Math.tan(fovYRad / 2) },
    state: { rotation: [...state.rotation], target: [tx, ty, tz], distance: d },
    target: [tx, ty, tz],
    up: [up[0], up[1], up[2]],
    fovYRad,
    near,
    far,
    sceneRadius,
    viewport: { width: viewport.width, height: viewport.height },
    view,
    projection,
  };
}

/** The link's cam=qx,qy,qz,qw,tx,ty,tz,d (as src/app/url-state.ts reads it), or null when it is not one. */
export function parseCam(text: string): ViewCameraState | null {
  const cam = text.split(',').map(Number);
  if (cam.length !== 8 || !cam.every(Number.isFinite) || !(cam[7] > 0)) return null;
  return { rotation: [cam[0], cam[1], cam[2], cam[3]], target: [cam[4], cam[5], cam[6]], distance: cam[7] };
}
