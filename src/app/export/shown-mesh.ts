// The surface on screen as one indexed mesh in the page's world units: voxel
// (i, j, k) at ((i, j, k) + origin) * voxel size (the file's, or what the user
// set). An in-core volume: the GPU's welded mesh (one vertex per cut grid edge,
// as VTK's merged points); a store: the step on screen, every level in
// level-0 voxels; cut by the page's clip as the renderer cuts it. Shared by
// the PLY and glTF exports and the measurement.
import { meshPositions } from '../../isosurface/vertex-format.ts';
import { clipMesh } from '../../core/clip.ts';
import type { Session } from '../session.ts';

export interface ShownMesh {
  /** xyz per vertex, world units. */
  positions: Float32Array;
  indices: Uint32Array;
  /** The isovalue on screen (as the user gave it, else the GPU's float32). */
  iso: number;
  voxelSize: [number, number, number];
  origin: [number, number, number];
  /** Voxel size 1 and no origin: world = voxel index space. */
  voxelUnits: boolean;
  dims: readonly number[];
}

/**
 * Null when no volume is open. `copy`: one of the other surfaces
 * (src/app/surfaces/: SurfaceSet.meshOf), at `iso`, read from its copy or
 * the store's step.
 */
export async function readShownMesh(
  session: Session,
  copy?: { iso: number; read: () => Promise<{ positions: Float32Array; indices: Uint32Array }> },
): Promise<ShownMesh | null> {
  const v = session.current;
  if (!v) return null;
  let mesh: { positions: Float32Array; indices: Uint32Array };
  if (copy) mesh = await copy.read();
  else if (v.iso.readPositions) mesh = await v.iso.readPositions();
  else {
    const surface = await v.iso.readMesh();
    mesh = { positions: meshPositions(surface), indices: surface.indices };
  }
  // what is shown: cut by the page's clip (level-0 voxel coordinates, as these positions)
  if (session.clip) mesh = clipMesh(mesh.positions, mesh.indices, session.clip);
  const voxelSize: [number, number, number] = [...session.spacing];
  const origin: [number, number, number] = [...(v.opened.origin ?? [0, 0, 0])];
  const voxelUnits = voxelSize.every((s) => s === 1) && origin.every((o) => o === 0);
  if (!voxelUnits) {
    const p = mesh.positions;
    for (let i = 0; i < p.length; i++) p[i] = (p[i] + origin[i % 3]) * voxelSize[i % 3];
  }
  return { ...mesh, iso: copy ? copy.iso : (session.drawnIsovalue ?? Number.NaN), voxelSize, origin, voxelUnits, dims: v.iso.info.dims };
}

/** Where the mesh's coordinates come from, one line (PLY comments, glTF asset extras). */
export function describePlacement(m: ShownMesh): string {
  const [sx, sy, sz] = m.voxelSize;
  const [ox, oy, oz] = m.origin;
  return m.voxelUnits
    ? `voxel index coordinates: voxel (i, j, k) at (i, j, k); volume ${m.dims.join(' x ')}`
    : `world coordinates: voxel (i, j, k) at ((i + ${ox}) * ${sx}, (j + ${oy}) * ${sy}, (k + ${oz}) * ${sz}); volume ${m.dims.join(' x ')}`;
}
