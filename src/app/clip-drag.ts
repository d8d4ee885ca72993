// The clip's handles in the view (src/render/clip-handles.ts draws them): a
// disc at the centre of each face of the clip box, and for the free plane its
// outline, a centre disc and a knob on a stick along its normal. Hovering a
// handle lights it; dragging one (no modifier needed) moves what it holds:
// - a face disc moves that face along its axis, to the point of the axis
//   nearest the pointer's ray (whole voxels, kept inside the volume and the
//   other face); Ctrl-drag (Cmd on a Mac) on a face itself does the same;
// - the centre disc moves the plane along its normal (the point of the
//   normal's line nearest the pointer's ray);
// - the knob turns the normal about the centre, which stays on the plane:
//   the knob goes where the pointer's ray meets the sphere it moves on.
// Moves are applied at most once per animation frame; a plane moved or
// turned off the volume (or out of the clip box) is refused.
import { mat4, vec4 } from 'gl-matrix';
import {
  boxFaceCentre,
  knobDirection,
  knobIsFar,
  nearestHandle,
  nearestOnLine,
  planeCentre,
  planeFromWorld,
  planeToWorld,
  projectToPixels,
} from '../core/clip-handles.ts';
import { boxEntryFace, type Clip, type ClipBox, type ClipPlane, freePlanePolygon, nearestOnAxis } from '../core/clip.ts';
import type { ArcballCamera } from '../render/camera.ts';
import type { ClipHandleLayer } from '../render/clip-handles.ts';

export interface ClipDragDeps {
  camera: ArcballCamera;
  /** The canvas in pixels (the camera's aspect). */
  size: () => { width: number; height: number };
  /** The clip now (level-0 voxels). */
  clip: () => Clip | undefined;
  /** The volume's level-0 grid points per axis. */
  dims: () => readonly number[];
  /** World = (voxel + origin) * voxel size. */
  placement: () => { voxelSize: readonly number[]; origin: readonly number[] };
  /** Moves one face (axis 0..2, side 0 lower / 1 upper) to a voxel coordinate. */
  setFace: (axis: number, side: 0 | 1, value: number) => void;
  /** A new plane (unit normal, level-0 voxels). */
  setPlane: (plane: ClipPlane) => void;
  /** Where the handles are listed. */
  layer: () => ClipHandleLayer;
  requestFrame: () => void;
}

/** Handles 0..5: the box's faces (axis + 3 side); 6 the plane's centre, 7 its knob. */
const CENTRE = 6;
const KNOB = 7;
const HANDLES = 8;
/** A disc's radius and a line's width, CSS pixels; a press this far from a disc's centre still takes it. */
const DISC_PX = 7;
const LIT_PX = 9;
const LINE_PX = 2;
const REACH_PX = 11;
/** The knob's stick, as a fraction of the volume's diagonal (world units). */
const STICK = 0.18;
const BOX_COLOR = [0.95, 0.68, 0.25];
const PLANE_COLOR = [0.35, 0.8, 1];
const LIT_COLOR = [1, 1, 0.75];

type Grabbed =
  | { kind: 'face'; axis: number; side: 0 | 1; point: [number, number, number]; start: number }
  | { kind: 'move'; centre: [number, number, number]; normal: [number, number, number]; s0: number }
  | { kind: 'turn'; centre: [number, number, number]; radius: number; far: boolean };

export class ClipDrag {
  #grabbed: Grabbed | undefined;
  /** The handle held or under the pointer (-1: none): drawn lit. */
  #lit = -1;
  /** World positions of the handles, and whether each is shown. */
  readonly #world = new Float64Array(3 * HANDLES);
  readonly #shown = new Array<boolean>(HANDLES).fill(false);
  /** The handles' pixel positions (NaN: not shown or behind the eye). */
  readonly #xy = new Float64Array(2 * HANDLES);
  /** The plane's outline (world) and its centre (voxels; kept while the plane moves, so the handle stays put). */
  #outline: number[][] = [];
  #centre: [number, number, number] | undefined;
  #stick = 1;
  #dims: readonly number[] = [];
  /** The latest pointer position of a drag, applied at the next animation frame. */
  #pending: [number, number] | undefined;
  #frame = 0;
  readonly #onFrame = (): void => {
    this.#frame = 0;
    this.#applyPending();
  };
  readonly #viewProj = mat4.create();
  readonly #inverse = mat4.create();
  readonly #ndc = vec4.create();
  readonly #p = vec4.create();
  readonly #px = [0, 0];

  constructor(private readonly d: ClipDragDeps) {}

  /**
   * The clip, the voxel size or the volume changed: the handles placed and
   * listed again. True when there is any to show.
   */
  refresh(): boolean {
    const clip = this.d.clip();
    const dims = this.d.dims();
    if (dims !== this.#dims) this.#centre = undefined;
    this.#dims = dims;
    const { voxelSize, origin } = this.d.placement();
    const toWorld = (p: readonly number[], i: number) => {
      for (let a = 0; a < 3; a++) this.#world[3 * i + a] = (p[a] + origin[a]) * voxelSize[a];
      this.#shown[i] = true;
    };
    this.#shown.fill(false);
    this.#outline = [];
    if (clip?.box) for (let f = 0; f < 6; f++) toWorld(boxFaceCentre(clip.box, f % 3, f < 3 ? 0 : 1), f);
    if (clip?.plane) {
      const polygon = freePlanePolygon(clip, dims);
      const [lo, hi] = this.#region(clip.box);
      this.#centre = planeCentre(clip.plane, polygon, lo, hi, this.#centre);
      this.#outline = polygon.map((p) => p.map((v, a) => (v + origin[a]) * voxelSize[a]));
      toWorld(this.#centre, CENTRE);
      const n = planeToWorld(clip.plane, voxelSize, origin).normal;
      this.#stick = STICK * Math.hypot(...[0, 1, 2].map((a) => Math.max(1, dims[a] - 1) * voxelSize[a]));
      for (let a = 0; a < 3; a++) this.#world[3 * KNOB + a] = this.#world[3 * CENTRE + a] + this.#stick * n[a];
      this.#shown[KNOB] = true;
    }
    if (this.#lit >= 0 && !this.#shown[this.#lit]) this.#lit = -1;
    this.#list();
    return this.#shown.includes(true);
  }

  /** The mouse at (u, v) with no button down: lights the handle under it; the cursor to show. */
  hover(u: number, v: number): string {
    const i = this.#grabbed ? this.#lit : this.#pick(u, v);
    if (i !== this.#lit) {
      this.#lit = i;
      this.#list();
    }
    return i >= 0 ? 'grab' : '';
  }

  /** A press at (u, v): true when it took a handle, or (with Ctrl/Cmd) a face of the box. */
  grab(u: number, v: number, modifier: boolean): boolean {
    const clip = this.d.clip();
    const i = this.#pick(u, v);
    if (i >= 0 && i < 6 && clip?.box) {
      const axis = i % 3,
        side = i < 3 ? 0 : 1;
      this.#grabbed = { kind: 'face', axis, side, point: boxFaceCentre(clip.box, axis, side), start: clip.box[i] };
    } else if ((i === CENTRE || i === KNOB) && clip?.plane) {
      const { voxelSize, origin } = this.d.placement();
      const centre = this.#handle(CENTRE);
      const ray = this.#ray(u, v, [0, 0, 0], [1, 1, 1]);
      if (i === CENTRE) {
        const normal = planeToWorld(clip.plane, voxelSize, origin).normal;
        const s0 = nearestOnLine(centre, normal, ray.origin, ray.dir);
        this.#grabbed = { kind: 'move', centre, normal, s0: Number.isFinite(s0) ? s0 : 0 };
      } else {
        const knob = this.#handle(KNOB);
        const n = [0, 1, 2].map((a) => knob[a] - centre[a]);
        this.#grabbed = { kind: 'turn', centre, radius: this.#stick, far: knobIsFar(n, ray.dir) };
      }
    } else if (modifier && clip?.box) {
      const box: ClipBox = clip.box;
      const { voxelSize, origin } = this.d.placement();
      const ray = this.#ray(u, v, origin, voxelSize);
      const hit = boxEntryFace(box, ray.origin, ray.dir);
      if (!hit) return false;
      this.#grabbed = { kind: 'face', ...hit, start: box[hit.axis + 3 * hit.side] };
    } else return false;
    this.#lit = i;
    this.#list();
    return true;
  }

  /** The pointer moved during a drag: applied at the next animation frame (the latest position only). */
  move(u: number, v: number): void {
    if (!this.#grabbed) return;
    this.#pending = [u, v];
    if (!this.#frame) this.#frame = requestAnimationFrame(this.#onFrame);
  }

  /** The drag ends: its last position applied now. */
  end(): void {
    if (this.#frame) cancelAnimationFrame(this.#frame);
    this.#frame = 0;
    this.#applyPending();
    this.#grabbed = undefined;
    this.#lit = -1;
    this.#list();
  }

  #applyPending(): void {
    const g = this.#grabbed;
    const at = this.#pending;
    this.#pending = undefined;
    if (!g || !at) return;
    const { voxelSize, origin } = this.d.placement();
    if (g.kind === 'face') {
      const ray = this.#ray(at[0], at[1], origin, voxelSize);
      const s = nearestOnAxis(g.point, g.axis, ray.origin, ray.dir);
      if (Number.isFinite(s)) this.d.setFace(g.axis, g.side, Math.round(g.start + s));
      return;
    }
    const ray = this.#ray(at[0], at[1], [0, 0, 0], [1, 1, 1]);
    let plane: ClipPlane, centre: number[];
    if (g.kind === 'move') {
      const s = nearestOnLine(g.centre, g.normal, ray.origin, ray.dir);
      if (!Number.isFinite(s)) return;
      centre = g.centre.map((c, a) => c + (s - g.s0) * g.normal[a]);
      plane = planeFromWorld(g.normal, centre, voxelSize, origin);
    } else {
      const n = knobDirection(g.centre, g.radius, ray.origin, ray.dir, g.far);
      if (!n) return;
      centre = g.centre;
      plane = planeFromWorld(n, centre, voxelSize, origin);
    }
    // refused when the plane would no longer cross what the volume and the box keep
    const box = this.d.clip()?.box;
    if (freePlanePolygon({ ...(box ? { box } : {}), plane }, this.#dims).length === 0) return;
    this.#centre = centre.map((w, a) => w / voxelSize[a] - origin[a]) as [number, number, number];
    this.d.setPlane(plane);
  }

  /** The volume's box, within the clip box if any (level-0 voxels). */
  #region(box: ClipBox | undefined): [number[], number[]] {
    const lo = [0, 0, 0],
      hi = this.#dims.map((n) => Math.max(0, n - 1));
    if (box) for (let a = 0; a < 3; a++) [lo[a], hi[a]] = [Math.max(lo[a], box[a]), Math.min(hi[a], box[a + 3])];
    return [lo, hi];
  }

  #handle(i: number): [number, number, number] {
    return [this.#world[3 * i], this.#world[3 * i + 1], this.#world[3 * i + 2]];
  }

  /** The handle under (u, v), within REACH_PX of its centre; -1 when none. */
  #pick(u: number, v: number): number {
    if (!this.#shown.includes(true)) return -1;
    const { width, height } = this.d.size();
    this.d.camera.aspect = width / height;
    this.d.camera.viewProjection(this.#viewProj);
    const p = [0, 0, 0];
    for (let i = 0; i < HANDLES; i++) {
      for (let a = 0; a < 3; a++) p[a] = this.#world[3 * i + a];
      const on = this.#shown[i] && projectToPixels(this.#viewProj, p, width, height, this.#px);
      this.#xy[2 * i] = on ? this.#px[0] : Number.NaN;
      this.#xy[2 * i + 1] = on ? this.#px[1] : Number.NaN;
    }
    return nearestHandle(this.#xy, HANDLES, u * width, v * height, REACH_PX * devicePixelRatio);
  }

  /** The pointer's ray: world units for scale 1 and offset 0, level-0 voxels given the placement (x / scale - offset). */
  #ray(u: number, v: number, offset: readonly number[], scale: readonly number[]): { origin: number[]; dir: number[] } {
    const { width, height } = this.d.size();
    this.d.camera.aspect = width / height;
    mat4.invert(this.#inverse, this.d.camera.viewProjection(this.#viewProj));
    const at = (depth: number) => {
      vec4.set(this.#ndc, u * 2 - 1, 1 - v * 2, depth, 1);
      vec4.transformMat4(this.#p, this.#ndc, this.#inverse);
      return [0, 1, 2].map((a) => this.#p[a] / this.#p[3] / scale[a] - offset[a]);
    };
    const near = at(0);
    const far = at(1);
    return { origin: near, dir: far.map((x, a) => x - near[a]) };
  }

  /** Lists the handles in the layer (the lit one larger and lighter). */
  #list(): void {
    const layer = this.d.layer();
    const dpr = devicePixelRatio;
    layer.clear();
    const plane = this.#shown[CENTRE];
    for (let k = 0; plane && k < this.#outline.length; k++)
      layer.line(this.#outline[k], this.#outline[(k + 1) % this.#outline.length], LINE_PX * dpr, PLANE_COLOR);
    if (plane) layer.line(this.#handle(CENTRE), this.#handle(KNOB), LINE_PX * dpr, this.#lit === KNOB ? LIT_COLOR : PLANE_COLOR);
    for (let i = 0; i < HANDLES; i++) {
      if (!this.#shown[i]) continue;
      const lit = i === this.#lit;
      layer.disc(this.#handle(i), (lit ? LIT_PX : DISC_PX) * dpr, lit ? LIT_COLOR : i < 6 ? BOX_COLOR : PLANE_COLOR);
    }
    layer.upload();
    this.d.requestFrame();
  }
}
