// What the page keeps when a store opens again at another time point
// (playback, the time slider): a new volume starts at the page's defaults
// (the camera fitted, no clip, the file's voxel size, one surface); another
// time point of the store on screen keeps the camera, the clip, a voxel size
// set here and every surface, as the page does for a lost device (main.ts).
import type { Clip } from '../../core/clip.ts';
import type { CameraState } from '../../render/camera.ts';
import type { Spacing } from '../ui/spacing-control.ts';
import type { SurfaceSpec } from '../url-state.ts';

export interface KeptPage {
  /** Session's values a new volume takes instead of its defaults (Session.install). */
  session: { pendingClip: Clip | undefined; pendingCamera: CameraState | undefined; pendingSpacing: Spacing | undefined };
  camera: CameraState;
  clip: Clip | undefined;
  spacing: Spacing;
  surfaces: { specs(): SurfaceSpec[]; selected: number; restore(specs: SurfaceSpec[], selected: number): Promise<void> };
}

/**
 * Sets the page's camera, clip and voxel size (when set here: it differs
 * from the store's) for the volume installed next; the function returned
 * puts the other surfaces back once it is installed.
 */
export function keepPageView(p: KeptPage, voxelSize: readonly number[]): () => Promise<void> {
  p.session.pendingCamera = p.camera;
  p.session.pendingClip = p.clip;
  p.session.pendingSpacing = p.spacing.some((v, a) => v !== voxelSize[a]) ? [...p.spacing] : undefined;
  const specs = p.surfaces.specs();
  const selected = p.surfaces.selected;
  return () => (specs.length > 1 ? p.surfaces.restore(specs, selected) : Promise.resolve());
}
