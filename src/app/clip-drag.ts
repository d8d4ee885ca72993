// Ctrl-drag (Cmd on a Mac) on a face of the clip box moves that face along
// its axis, following the pointer: the ray under the pointer is taken to the
// volume's voxels, the face it enters first is grabbed, and each move puts
// the face at the point of its axis nearest the pointer's ray (whole voxels).
import { mat4 } from 'gl-matrix';
import { boxEntryFace, type ClipBox, nearestOnAxis } from '../core/clip.ts';
import type { ArcballCamera } from '../render/camera.ts';
import { unproject } from '../render/viewer.ts';

export interface ClipDragDeps {
  camera: ArcballCamera;
  /** The canvas in pixels (the camera's aspect). */
  size: () => { width: number; height: number };
  /** The clip box now (level-0 voxels), or undefined when it is off. */
  box: () => ClipBox | undefined;
  /** World = (voxel + origin) * voxel size. */
  placement: () => { voxelSize: readonly number[]; origin: readonly number[] };
  /** Moves one face (axis 0..2, side 0 lower / 1 upper) to a voxel coordinate. */
  setFace: (axis: number, side: 0 | 1, value: number) => void;
}

export class ClipBoxDrag {
  #grabbed: { axis: number; side: 0 | 1; point: [number, number, number]; start: number } | undefined;

  constructor(private readonly d: ClipDragDeps) {}

  /** A Ctrl-drag starts at (u, v): true when it grabbed a face of the box. */
  grab(u: number, v: number): boolean {
    const box = this.d.box();
    if (!box) return false;
    const ray = this.#ray(u, v);
    const hit = boxEntryFace(box, ray.origin, ray.dir);
    if (!hit) return false;
    this.#grabbed = { ...hit, start: box[hit.axis + 3 * hit.side] };
    return true;
  }

  move(u: number, v: number): void {
    const g = this.#grabbed;
    if (!g) return;
    const ray = this.#ray(u, v);
    const s = nearestOnAxis(g.point, g.axis, ray.origin, ray.dir);
    if (Number.isFinite(s)) this.d.setFace(g.axis, g.side, Math.round(g.start + s));
  }

  end(): void {
    this.#grabbed = undefined;
  }

  /** The pointer's ray in level-0 voxels. */
  #ray(u: number, v: number): { origin: number[]; dir: number[] } {
    const { width, height } = this.d.size();
    this.d.camera.aspect = width / height;
    const viewProj = this.d.camera.viewProjection(mat4.create());
    const ndc = [u * 2 - 1, 1 - v * 2];
    const { voxelSize, origin } = this.d.placement();
    const toVoxel = (w: number[]) => w.map((x, a) => x / voxelSize[a] - origin[a]);
    const near = toVoxel(unproject(viewProj, [...ndc, 0]));
    const far = toVoxel(unproject(viewProj, [...ndc, 1]));
    return { origin: near, dir: far.map((x, a) => x - near[a]) };
  }
}
