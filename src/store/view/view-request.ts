// The view a store is refined by, as the CLI and links give it: a box in
// level-0 voxels framed as the page's Fit frames it (--view-box), or the
// page's link (--view '#iso=..&cam=..&px=W,H&tol=T'). Both become the same
// ViewSpec the page's camera gives (cut.ts: the page's camera math), so a
// headless run computes the page's cut for that camera.
import { type Box0, cameraForBox, cameraFromView, fitBox0, parseCam, sceneRadiusOf, type Viewport } from './camera.ts';
import { DEFAULT_TOLERANCE_PX, type ViewSpec } from './cut-types.ts';

export interface ViewRequest {
  /** A box in level-0 voxels, x0,y0,z0,x1,y1,z1. */
  box?: Box0;
  /** The page's link (its hash: #iso=..&cam=..[&px=W,H][&tol=T]). */
  link?: string;
  /** Pixels (over the link's tol=, over the default 1.5). */
  tolerancePx?: number;
  /** Cover level seams with skirts (default true; --no-skirts). */
  skirts?: boolean;
  /** The canvas the view is drawn on (`render --size`): over the link's px=, over the default. */
  viewport?: Viewport;
  /** Neither a box nor a link: the page's Fit of the whole of level 0. */
  whole?: boolean;
}

/** The view's canvas when neither the request nor the link says: 1280x800 at device pixel ratio 1. */
export const DEFAULT_VIEWPORT: Viewport = { width: 1280, height: 800 };

/** x0,y0,z0,x1,y1,z1 -> the box, or why it is not one. */
export function parseViewBox(text: string): Box0 | string {
  const v = text.split(',').map((s) => Number(s.trim()));
  if (v.length !== 6 || !v.every(Number.isFinite)) return 'six numbers x0,y0,z0,x1,y1,z1 (level-0 voxels)';
  if (!(v[3] > v[0] && v[4] > v[1] && v[5] > v[2])) return 'the box must have x1 > x0, y1 > y0 and z1 > z0';
  return v as Box0;
}

/** The link's canvas (px=W,H) and tolerance (tol=T), when it has them. */
export function linkViewFields(hash: string): { viewport?: Viewport; tolerancePx?: number } {
  const p = new URLSearchParams(hash.replace(/^#/, ''));
  const out: { viewport?: Viewport; tolerancePx?: number } = {};
  const px = p.get('px')?.split(',').map(Number);
  if (px && px.length === 2 && px.every((n) => Number.isInteger(n) && n > 0 && n <= 16384)) out.viewport = { width: px[0], height: px[1] };
  const tol = Number(p.get('tol'));
  if (p.has('tol') && tol > 0 && tol <= 1000) out.tolerancePx = tol;
  return out;
}

/**
 * The ViewSpec of a request over a store of these levels: the box framed by
 * the page's Fit on the default canvas, or the link's camera on the link's
 * canvas (near and far as the page's, which fits level 0's box in this
 * mode). Throws a RangeError naming what is wrong with the link.
 */
export function viewSpecFor(
  req: ViewRequest,
  levels: readonly { dims: [number, number, number] }[],
  voxelSize: [number, number, number],
): ViewSpec {
  // near and far as the page's while it shows this store: from the volume's radius (level 0's box)
  const sceneRadius = sceneRadiusOf(fitBox0(levels[0], 0), voxelSize);
  const box = req.box ?? (req.whole && req.link === undefined ? fitBox0(levels[0], 0) : undefined);
  if (box) {
    // framed as Fit frames a box (its direction and distance), in the page's scene of the whole volume
    const viewport = req.viewport ?? DEFAULT_VIEWPORT;
    const framed = cameraForBox(box, voxelSize, viewport);
    return {
      camera: cameraFromView(framed.state, viewport, sceneRadius),
      tolerancePx: req.tolerancePx ?? DEFAULT_TOLERANCE_PX,
    };
  }
  const hash = req.link ?? '';
  const cam = new URLSearchParams(hash.replace(/^#/, '').replace(/^.*#/, '')).get('cam');
  const state = cam ? parseCam(cam) : null;
  if (!state) throw new RangeError(`the view link has no camera (cam=qx,qy,qz,qw,tx,ty,tz,d): ${hash}`);
  const fields = linkViewFields(hash.replace(/^.*#/, ''));
  const viewport = req.viewport ?? fields.viewport ?? DEFAULT_VIEWPORT;
  return {
    camera: cameraFromView(state, viewport, sceneRadius),
    tolerancePx: req.tolerancePx ?? fields.tolerancePx ?? DEFAULT_TOLERANCE_PX,
  };
}
