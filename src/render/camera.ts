// Arcball camera around a target: rotation as a quaternion (free rotation
// like ParaView/VTK trackballs), distance for zoom, target for pan. Shared
// by every page. State is plain numbers so it fits in a URL hash.

import { mat4, quat, vec3 } from 'gl-matrix';
import { FOV_Y_RAD, fitDistance, fitRotation, nearFar, type UpAxis, viewMatrix } from '../core/camera.ts';

export type { UpAxis };

export interface CameraState {
  /** Rotation from world to eye orientation, [x, y, z, w]. */
  rotation: [number, number, number, number];
  target: [number, number, number];
  distance: number;
}

export interface Bounds {
  min: [number, number, number];
  max: [number, number, number];
}

export class ArcballCamera {
  readonly rotation = quat.create();
  readonly target = vec3.create();
  distance = 3;
  fovY = FOV_Y_RAD;
  aspect = 1;
  private home: CameraState;
  private sceneRadius = 1;

  constructor() {
    this.home = this.getState();
  }

  /** Frames `bounds` from a three-quarter view with `up` pointing up, and makes that the reset view. */
  fit(bounds: Bounds, up: UpAxis = 'z'): void {
    const c = vec3.fromValues(
      (bounds.min[0] + bounds.max[0]) / 2,
      (bounds.min[1] + bounds.max[1]) / 2,
      (bounds.min[2] + bounds.max[2]) / 2,
    );
    const r = 0.5 * vec3.distance(vec3.fromValues(...bounds.min), vec3.fromValues(...bounds.max));
    this.sceneRadius = Math.max(r, 1e-6);
    vec3.copy(this.target, c);
    fitRotation(this.rotation, up);
    this.distance = fitDistance(this.sceneRadius, this.fovY);
    this.home = this.getState();
  }

  /** Centres `bounds` and zooms to show them whole, keeping the current direction. */
  frameBounds(bounds: Bounds): void {
    const r = 0.5 * vec3.distance(vec3.fromValues(...bounds.min), vec3.fromValues(...bounds.max));
    this.sceneRadius = Math.max(r, 1e-6);
    vec3.set(this.target, (bounds.min[0] + bounds.max[0]) / 2, (bounds.min[1] + bounds.max[1]) / 2, (bounds.min[2] + bounds.max[2]) / 2);
    this.distance = fitDistance(this.sceneRadius, this.fovY);
  }

  reset(): void {
    this.setState(this.home);
  }

  getState(): CameraState {
    const r = this.rotation;
    const t = this.target;
    return { rotation: [r[0], r[1], r[2], r[3]], target: [t[0], t[1], t[2]], distance: this.distance };
  }

  setState(s: CameraState): void {
    quat.set(this.rotation, ...s.rotation);
    quat.normalize(this.rotation, this.rotation);
    vec3.set(this.target, ...s.target);
    this.distance = s.distance;
  }

  view(out = mat4.create()): mat4 {
    return viewMatrix(out, this.rotation, this.target, this.distance);
  }

  projection(out = mat4.create()): mat4 {
    const [near, far] = nearFar(this.distance, this.sceneRadius);
    // WebGPU clip space has z in [0, 1].
    return mat4.perspectiveZO(out, this.fovY, this.aspect, near, far);
  }

  viewProjection(out = mat4.create()): mat4 {
    // (scratchP/scratchView: no allocation per frame; out may not alias them)
    return mat4.multiply(out, this.projection(scratchP), this.view(scratchView));
  }

  eyePosition(out = vec3.create()): vec3 {
    const inv = quat.invert(scratchQ, this.rotation);
    vec3.transformQuat(out, vec3.set(scratchV, 0, 0, this.distance), inv);
    return vec3.add(out, out, this.target);
  }

  /** Arcball rotation between two points in normalized device coords ([-1,1]^2). */
  rotateArcball(x0: number, y0: number, x1: number, y1: number): void {
    const a = arcballVector(x0, y0);
    const b = arcballVector(x1, y1);
    const axis = vec3.cross(vec3.create(), a, b);
    const len = vec3.length(axis);
    if (len < 1e-9) return;
    const angle = Math.atan2(len, vec3.dot(a, b)) * 2;
    const dq = quat.setAxisAngle(quat.create(), vec3.scale(axis, axis, 1 / len), angle);
    // The axis is in eye space: apply after the current rotation.
    quat.multiply(this.rotation, dq, this.rotation);
    quat.normalize(this.rotation, this.rotation);
  }

  /** Pans by a fraction of the view height (dx, dy in NDC units). */
  pan(dx: number, dy: number): void {
    const h = 2 * this.distance * Math.tan(this.fovY / 2);
    const inv = quat.invert(quat.create(), this.rotation);
    const move = vec3.fromValues((-dx * h * this.aspect) / 2, (-dy * h) / 2, 0);
    vec3.transformQuat(move, move, inv);
    vec3.add(this.target, this.target, move);
  }

  /** Zoom by a factor (< 1 moves closer). */
  zoom(factor: number): void {
    this.distance = Math.min(Math.max(this.distance * factor, this.sceneRadius * 0.02), this.sceneRadius * 50);
  }
}

// Scratch for the per-frame matrices (view, viewProjection, eyePosition): the
// render loop allocates nothing. Each is used within one call only.
const scratchV = vec3.create();
const scratchQ = quat.create();
const scratchP = mat4.create();
const scratchView = mat4.create();

function arcballVector(x: number, y: number): vec3 {
  const d = x * x + y * y;
  // Sphere inside radius 1/sqrt(2), hyperbolic sheet outside (Bell's trackball).
  const z = d <= 0.5 ? Math.sqrt(1 - d) : 0.5 / Math.sqrt(d);
  return vec3.normalize(vec3.create(), vec3.fromValues(x, y, z));
}
