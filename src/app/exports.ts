// What a user takes away: the view as PNG, the surface as binary PLY or
// glTF, and a link that reopens this view.

import type { Viewer } from '../render/viewer.ts';
import { download } from './dom.ts';
import { captureViewPng } from './export/screenshot.ts';
import { encodeGlb, type GlbSurface } from '../mc/glb.ts';
import { measureSurface } from '../mc/mesh-measure.ts';
import { encodePly } from '../mc/ply.ts';
import { describePlacement, readShownMesh, type ShownMesh } from './export/shown-mesh.ts';
import type { SurfaceSet } from './surfaces/surface-set.ts';
import { formatBytes } from './format.ts';
import type { Messages } from './messages.ts';
import { type MeasuredSurface, measuresToCsv } from './ui/measure-panel.ts';
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
  try {
    const mesh = await readShownMesh(session);
    if (!mesh) return;
    if (mesh.indices.length === 0) {
      messages.show('The surface is empty at this isovalue: nothing to export.', 'info', 4000);
      return;
    }
    const ply = encodePly(mesh, [
      `isosurface of ${session.current?.opened.name} at isovalue ${mesh.iso}`,
      describePlacement(mesh),
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

/** The visible surfaces as binary glTF: a mesh each, with its colour and opacity as material, in world units. */
export async function saveGlb(session: Session, surfaces: SurfaceSet, messages: Messages): Promise<void> {
  try {
    const parts: GlbSurface[] = [];
    let about: ShownMesh | undefined;
    for (const entry of surfaces.entries) {
      if (!entry.visible) continue;
      const mesh = await readShownMesh(session, surfaces.meshOf(entry));
      if (!mesh) return;
      about ??= mesh;
      if (mesh.indices.length === 0) continue;
      const measure = measureSurface(mesh.positions, mesh.indices);
      parts.push({
        name: `iso ${Number(mesh.iso.toPrecision(7))}`,
        positions: mesh.positions,
        indices: mesh.indices,
        color: entry.color,
        opacity: entry.opacity,
        extras: { isovalue: mesh.iso, area: measure.area, enclosedVolume: measure.enclosedVolume },
      });
    }
    if (parts.length === 0 || !about) {
      messages.show('No visible surface has triangles: nothing to export.', 'info', 4000);
      return;
    }
    const glb = await encodeGlb(parts, {
      generator: 'zfp-isosurface-webgpu',
      extras: { source: session.current?.opened.name, coordinates: describePlacement(about) },
    });
    download(new Blob([glb as BlobPart], { type: 'model/gltf-binary' }), `${baseName(session)}${isoTag(session)}.glb`);
    const triangles = parts.reduce((n, p) => n + p.indices.length / 3, 0);
    messages.show(
      `Exported ${parts.length} surface${parts.length > 1 ? 's' : ''}, ${triangles.toLocaleString('en-US')} triangles, as glTF (${formatBytes(glb.byteLength)}).`,
      'info',
      4000,
    );
  } catch (e) {
    messages.show(`glTF export: ${(e as Error).message}`);
  }
}

/** Area and enclosed volume of every visible surface (world units, cut by the clip); null when nothing is open or it failed (the message says why). */
export async function measureShown(session: Session, surfaces: SurfaceSet, messages: Messages): Promise<MeasuredSurface[] | null> {
  try {
    const out: MeasuredSurface[] = [];
    for (const entry of surfaces.entries) {
      if (!entry.visible) continue;
      const mesh = await readShownMesh(session, surfaces.meshOf(entry));
      if (!mesh) return null;
      out.push({
        ...measureSurface(mesh.positions, mesh.indices),
        iso: mesh.iso,
        voxelUnits: mesh.voxelUnits,
        selected: entry === surfaces.selectedEntry,
        color: entry.color,
        opacity: entry.opacity,
      });
    }
    return out;
  } catch (e) {
    messages.show(`Measure: ${(e as Error).message}`);
    return null;
  }
}

/** The measurements (and the picked points, the clip and the volume) as JSON, or the surfaces as CSV. */
export function saveMeasures(
  session: Session,
  format: 'json' | 'csv',
  all: MeasuredSurface[],
  extra: { clip: unknown; picks: unknown },
): void {
  const name = `${baseName(session)}_measures.${format}`;
  if (format === 'csv') {
    download(new Blob([measuresToCsv(all)], { type: 'text/csv' }), name);
    return;
  }
  const v = session.current;
  const record = {
    volume: v ? { name: v.opened.name, dims: v.iso.info.dims, voxelSize: session.spacing, origin: v.opened.origin ?? [0, 0, 0] } : null,
    units: all[0]?.voxelUnits ? 'voxel' : 'world (voxel size applied)',
    clip: extra.clip ?? null,
    surfaces: all,
    picks: extra.picks ?? null,
  };
  download(new Blob([`${JSON.stringify(record, null, 2)}\n`], { type: 'application/json' }), name);
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
