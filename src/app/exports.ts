// What a user takes away: the view as PNG, the surface as binary PLY, and a
// link that reopens this view.

import type { Viewer } from '../render/viewer.ts';
import { download } from './dom.ts';
import { captureViewPng } from './export/screenshot.ts';
import { meshPositions } from '../isosurface/vertex-format.ts';
import { encodePly } from '../mc/ply.ts';
import { formatBytes } from './format.ts';
import type { Messages } from './messages.ts';
import type { Session } from './session.ts';
import type { ViewLink } from './view-link.ts';

function baseName(session: Session): string {
  const v = session.current;
  if (!v) return 'surface';
  const name = v.opened.kind === 'default' ? 'default' : v.opened.name.replace(/\.(raw|zfp|nrrd)(\..*)?$/i, '').replace(/\.[^.]*$/, '');
  return name.replace(/[^\w.-]+/g, '_');
}

function isoTag(session: Session): string {
  const iso = session.drawnIsovalue;
  return iso === undefined ? '' : `_iso${Number(iso.toPrecision(6))}`;
}

export async function savePng(viewer: Viewer, session: Session, messages: Messages): Promise<void> {
  try {
    const blob = await captureViewPng(viewer);
    download(blob, `${baseName(session)}${isoTag(session)}.png`);
  } catch (e) {
    messages.show(`Screenshot: ${(e as Error).message}`);
  }
}

export async function savePly(session: Session, messages: Messages): Promise<void> {
  const v = session.current;
  if (!v) return;
  try {
    // a store refined by the view: every level's piece, in level-0 voxels
    let mesh: { positions: Float32Array; indices: Uint32Array };
    if (v.iso.readPositions) mesh = await v.iso.readPositions();
    else {
      const surface = await v.iso.readMesh();
      // Welded on the GPU: one vertex per cut grid edge, as VTK's merged points.
      mesh = { positions: meshPositions(surface), indices: surface.indices };
    }
    if (mesh.indices.length === 0) {
      messages.show('The surface is empty at this isovalue: nothing to export.', 'info', 4000);
      return;
    }
    // What is on screen: voxel (i, j, k) at (i, j, k) * voxel size (1 unless the file or the user gave one).
    const size = session.spacing;
    const origin = v.opened.origin ?? [0, 0, 0];
    const isotropicUnit = size.every((s) => s === 1) && origin.every((o) => o === 0);
    if (!isotropicUnit) {
      for (let i = 0; i < mesh.positions.length; i++) mesh.positions[i] = (mesh.positions[i] + origin[i % 3]) * size[i % 3];
    }
    const iso = session.drawnIsovalue ?? NaN;
    const ply = encodePly(mesh, [
      `isosurface of ${v.opened.name} at isovalue ${iso}`,
      isotropicUnit
        ? `voxel index coordinates: voxel (i, j, k) at (i, j, k); volume ${v.iso.info.dims.join(' x ')}`
        : `world coordinates: voxel (i, j, k) at ((i + ${origin[0]}) * ${size[0]}, (j + ${origin[1]}) * ${size[1]}, (k + ${origin[2]}) * ${size[2]}); volume ${v.iso.info.dims.join(' x ')}`,
      'made by zfp-isosurface-webgpu (marching cubes on the GPU, zfp fixed-rate blocks)',
    ]);
    download(new Blob([ply as BlobPart], { type: 'application/octet-stream' }), `${baseName(session)}${isoTag(session)}.ply`);
    messages.show(
      `Exported ${(mesh.indices.length / 3).toLocaleString('en-US')} triangles, ${(mesh.positions.length / 3).toLocaleString('en-US')} vertices (${formatBytes(ply.byteLength)}).`,
      'info',
      4000,
    );
  } catch (e) {
    messages.show(`PLY export: ${(e as Error).message}`);
  }
}

export async function copyLink(link: ViewLink, messages: Messages): Promise<void> {
  link.flush();
  const href = link.href();
  try {
    await navigator.clipboard.writeText(href);
    messages.show('Link to this view copied.', 'info', 2500);
  } catch {
    // No clipboard permission (e.g. not a secure context): show it to copy by hand.
    messages.show(`Link to this view: ${href}`, 'info');
  }
}
