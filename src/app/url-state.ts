// The view in the URL hash, so a link reopens the same surface and camera:
// #iso=0.5&cam=qx,qy,qz,qw,tx,ty,tz,d[&vox=sx,sy,sz] (vox: a voxel size the
// user set, over the file's); several surfaces: iso=a,b,c with op=.. (opacity),
// col=rrggbb,.. (colour), vis=1,0,.. (shown) and sel=k (the one the slider moves);
// clip=x0,y0,z0,x1,y1,z1 and plane=nx,ny,nz,d (src/core/clip.ts, level-0 voxels); for stores also level=L, and for stores of
// lossless chunks rate=R (their bricks' GPU rate), t=T and c=C (time point
// and channel), cut=1|0 (refine by the view or level by level) with px=W,H
// (the canvas) and tol=T (pixels), tint=1 (tint by level); draw=rays (the surface ray cast in the
// block cache, not drawn as triangles). The volume itself comes from ?url=... (same
// origin) or is the built-in default.
import type { CameraState } from '../render/camera.ts';
import { type Clip, parseClipBox, parseClipPlane } from '../core/clip.ts';

/** One surface of several (src/app/surfaces/). */
export interface SurfaceSpec {
  iso: number;
  color?: [number, number, number];
  opacity?: number;
  visible?: boolean;
}

export interface ViewState {
  /** The isovalue of the surface the slider moves. */
  iso?: number;
  /** Several surfaces (absent: one, at `iso`); `iso` is surfaces[selected].iso. */
  surfaces?: SurfaceSpec[];
  selected?: number;
  /** The clip box and plane (level-0 voxels). */
  clip?: Clip;
  camera?: CameraState;
  /** Voxel size set by the user (absent: the file's own). */
  spacing?: [number, number, number];
  /** The level of a store shown (src/app/store/): a link reopens that level. */
  level?: number;
  /** A store of lossless chunks: the GPU rate of its bricks, the time point and channel shown. */
  storeRate?: number;
  time?: number;
  channel?: number;
  /** A store refined by the view (cut=1) or level by level (cut=0); absent: the page decides. */
  cut?: boolean;
  /** With cut: the canvas in device pixels (px=W,H) and the pixel tolerance (tol=T), so a link (and the CLI's --view) refines the same cut; tint=1 tints by level. */
  viewport?: { width: number; height: number };
  tolerancePx?: number;
  tint?: boolean;
  /** How the surface is drawn: its triangles (mesh, the default) or ray cast in the block cache (draw=rays). */
  draw?: 'mesh' | 'rays';
}

const round = (x: number) => Number(x.toPrecision(7));
const hex = (c: readonly number[]) =>
  c
    .map((v) =>
      Math.round(Math.min(1, Math.max(0, v)) * 255)
        .toString(16)
        .padStart(2, '0'),
    )
    .join('');

export function encodeViewState(s: ViewState): string {
  const parts: string[] = [];
  const many = s.surfaces?.filter((e) => Number.isFinite(e.iso));
  if (many && (many.length > 1 || many.some((e) => (e.opacity ?? 1) !== 1 || e.visible === false))) {
    parts.push(`iso=${many.map((e) => round(e.iso)).join(',')}`);
    if (many.some((e) => (e.opacity ?? 1) !== 1)) parts.push(`op=${many.map((e) => round(e.opacity ?? 1)).join(',')}`);
    if (many.some((e) => e.color)) parts.push(`col=${many.map((e) => hex(e.color ?? [1, 1, 1])).join(',')}`);
    if (many.some((e) => e.visible === false)) parts.push(`vis=${many.map((e) => (e.visible === false ? 0 : 1)).join(',')}`);
    if (s.selected !== undefined && s.selected > 0 && s.selected < many.length) parts.push(`sel=${s.selected}`);
  } else if (s.iso !== undefined && Number.isFinite(s.iso)) parts.push(`iso=${round(s.iso)}`);
  if (s.camera) {
    const c = s.camera;
    parts.push(`cam=${[...c.rotation, ...c.target, c.distance].map(round).join(',')}`);
  }
  if (s.clip?.box) parts.push(`clip=${s.clip.box.map(round).join(',')}`);
  if (s.clip?.plane) parts.push(`plane=${[...s.clip.plane.normal, s.clip.plane.d].map(round).join(',')}`);
  if (s.spacing) parts.push(`vox=${s.spacing.map(round).join(',')}`);
  if (s.level !== undefined) parts.push(`level=${s.level}`);
  if (s.storeRate !== undefined) parts.push(`rate=${round(s.storeRate)}`);
  if (s.time !== undefined) parts.push(`t=${s.time}`);
  if (s.channel !== undefined) parts.push(`c=${s.channel}`);
  if (s.cut !== undefined) parts.push(`cut=${s.cut ? 1 : 0}`);
  if (s.viewport) parts.push(`px=${s.viewport.width},${s.viewport.height}`);
  if (s.tolerancePx !== undefined) parts.push(`tol=${round(s.tolerancePx)}`);
  if (s.tint) parts.push('tint=1');
  if (s.draw === 'rays') parts.push('draw=rays');
  return parts.join('&');
}

export function decodeViewState(hash: string): ViewState {
  const params = new URLSearchParams(hash.replace(/^#/, ''));
  const out: ViewState = {};
  const isos = (params.get('iso') ?? '').split(',').map((v) => (v.trim() === '' ? Number.NaN : Number(v)));
  if (params.has('iso') && isos.length === 1 && Number.isFinite(isos[0])) out.iso = isos[0];
  else if (params.has('iso') && isos.length > 1 && isos.length <= 8 && isos.every(Number.isFinite)) {
    const ops = params.get('op')?.split(',').map(Number);
    const cols = params.get('col')?.split(',');
    const vis = params.get('vis')?.split(',');
    out.surfaces = isos.map((iso, i) => {
      const spec: SurfaceSpec = { iso };
      const op = ops?.[i];
      if (op !== undefined && op > 0 && op <= 1) spec.opacity = op;
      const col = cols?.[i];
      if (col && /^[0-9a-f]{6}$/i.test(col))
        spec.color = [0, 2, 4].map((k) => Number.parseInt(col.slice(k, k + 2), 16) / 255) as [number, number, number];
      if (vis?.[i] === '0') spec.visible = false;
      return spec;
    });
    const sel = Number(params.get('sel') ?? 0);
    out.selected = Number.isInteger(sel) && sel >= 0 && sel < isos.length ? sel : 0;
    out.iso = isos[out.selected];
  }
  const cam = params.get('cam')?.split(',').map(Number);
  if (cam && cam.length === 8 && cam.every(Number.isFinite) && cam[7] > 0) {
    out.camera = {
      rotation: [cam[0], cam[1], cam[2], cam[3]],
      target: [cam[4], cam[5], cam[6]],
      distance: cam[7],
    };
  }
  const box = params.has('clip') ? parseClipBox(params.get('clip')!) : undefined;
  const plane = params.has('plane') ? parseClipPlane(params.get('plane')!) : undefined;
  if ((box && typeof box !== 'string') || (plane && typeof plane !== 'string')) {
    out.clip = {
      ...(box && typeof box !== 'string' ? { box } : {}),
      ...(plane && typeof plane !== 'string' ? { plane } : {}),
    };
  }
  const vox = params.get('vox')?.split(',').map(Number);
  if (vox && vox.length === 3 && vox.every((v) => Number.isFinite(v) && v > 0)) out.spacing = [vox[0], vox[1], vox[2]];
  const level = Number(params.get('level'));
  if (params.has('level') && Number.isInteger(level) && level >= 0 && level < 64) out.level = level;
  const rate = Number(params.get('rate'));
  if (params.has('rate') && rate > 0 && rate <= 32) out.storeRate = rate;
  for (const [key, field] of [
    ['t', 'time'],
    ['c', 'channel'],
  ] as const) {
    const v = Number(params.get(key));
    if (params.has(key) && Number.isInteger(v) && v >= 0 && v < 2 ** 31) out[field] = v;
  }
  if (params.get('cut') === '1') out.cut = true;
  else if (params.get('cut') === '0') out.cut = false;
  const px = params.get('px')?.split(',').map(Number);
  if (px && px.length === 2 && px.every((n) => Number.isInteger(n) && n > 0 && n <= 16384)) out.viewport = { width: px[0], height: px[1] };
  const tol = Number(params.get('tol'));
  if (params.has('tol') && tol > 0 && tol <= 1000) out.tolerancePx = tol;
  if (params.get('tint') === '1') out.tint = true;
  if (params.get('draw') === 'rays') out.draw = 'rays';
  return out;
}

/** Why a link's clip= or plane= was not used (decodeViewState leaves them out), one sentence each. */
export function clipProblems(hash: string): string[] {
  const params = new URLSearchParams(hash.replace(/^#/, ''));
  const out: string[] = [];
  const box = params.has('clip') ? parseClipBox(params.get('clip')!) : undefined;
  if (typeof box === 'string') out.push(`The link's clip=${params.get('clip')} is not a clip box (${box}); nothing is cut by it.`);
  const plane = params.has('plane') ? parseClipPlane(params.get('plane')!) : undefined;
  if (typeof plane === 'string') out.push(`The link's plane=${params.get('plane')} is not a plane (${plane}); nothing is cut by it.`);
  return out;
}

/** Updates the hash without adding history entries (scrubbing would flood it). */
export function writeViewState(s: ViewState): void {
  const hash = encodeViewState(s);
  const url = `${location.pathname}${location.search}${hash ? `#${hash}` : ''}`;
  history.replaceState(null, '', url);
}
