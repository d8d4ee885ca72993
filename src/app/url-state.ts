// The view in the URL hash, so a link reopens the same surface and camera:
// #iso=0.5&cam=qx,qy,qz,qw,tx,ty,tz,d[&vox=sx,sy,sz] (vox: a voxel size the
// user set, over the file's); for stores also level=L, and for stores of
// lossless chunks rate=R (their bricks' GPU rate), t=T and c=C (time point
// and channel), cut=1|0 (refine by the view or level by level) with px=W,H
// (the canvas) and tol=T (pixels), tint=1 (tint by level). The volume itself comes from ?url=... (same
// origin) or is the built-in default.
import type { CameraState } from '../render/camera.ts';

export interface ViewState {
  iso?: number;
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
}

const round = (x: number) => Number(x.toPrecision(7));

export function encodeViewState(s: ViewState): string {
  const parts: string[] = [];
  if (s.iso !== undefined && Number.isFinite(s.iso)) parts.push(`iso=${round(s.iso)}`);
  if (s.camera) {
    const c = s.camera;
    parts.push(`cam=${[...c.rotation, ...c.target, c.distance].map(round).join(',')}`);
  }
  if (s.spacing) parts.push(`vox=${s.spacing.map(round).join(',')}`);
  if (s.level !== undefined) parts.push(`level=${s.level}`);
  if (s.storeRate !== undefined) parts.push(`rate=${round(s.storeRate)}`);
  if (s.time !== undefined) parts.push(`t=${s.time}`);
  if (s.channel !== undefined) parts.push(`c=${s.channel}`);
  if (s.cut !== undefined) parts.push(`cut=${s.cut ? 1 : 0}`);
  if (s.viewport) parts.push(`px=${s.viewport.width},${s.viewport.height}`);
  if (s.tolerancePx !== undefined) parts.push(`tol=${round(s.tolerancePx)}`);
  if (s.tint) parts.push('tint=1');
  return parts.join('&');
}

export function decodeViewState(hash: string): ViewState {
  const params = new URLSearchParams(hash.replace(/^#/, ''));
  const out: ViewState = {};
  const iso = Number(params.get('iso'));
  if (params.has('iso') && Number.isFinite(iso)) out.iso = iso;
  const cam = params.get('cam')?.split(',').map(Number);
  if (cam && cam.length === 8 && cam.every(Number.isFinite) && cam[7] > 0) {
    out.camera = {
      rotation: [cam[0], cam[1], cam[2], cam[3]],
      target: [cam[4], cam[5], cam[6]],
      distance: cam[7],
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
  return out;
}

/** Updates the hash without adding history entries (scrubbing would flood it). */
export function writeViewState(s: ViewState): void {
  const hash = encodeViewState(s);
  const url = `${location.pathname}${location.search}${hash ? `#${hash}` : ''}`;
  history.replaceState(null, '', url);
}
