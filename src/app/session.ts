// The volume on screen: its Isosurface, what the panel shows about it, and
// the switch to a newly loaded one (the old one is freed only after the new
// one has its first surface, so a failed load leaves it untouched).

import { IsosurfaceBudgetError, type IsosurfaceStats } from '../isosurface/types.ts';
import type { BoxLayer } from '../render/box-layer.ts';
import type { RayLayer } from '../render/ray-layer.ts';
import type { SurfaceLayer } from '../render/surface-layer.ts';
import type { Viewer } from '../render/viewer.ts';
import type { CameraState } from '../render/camera.ts';
import { formatBytes, formatIso } from './format.ts';
import { setInfoList } from './info-list.ts';
import type { LoadedVolume } from './loading/loader.ts';
import type { Messages } from './messages.ts';
import type { PageState } from './page-state.ts';
import { computeBlockProfile } from './ui/block-profile.ts';
import type { BenchPanel } from './ui/bench-panel.ts';
import type { BudgetControl } from './ui/budget-control.ts';
import type { Hud } from './ui/hud.ts';
import type { IsoControl } from './ui/iso-control.ts';
import type { Clip } from '../core/clip.ts';
import type { ClipControl } from './ui/clip-control.ts';
import type { CapLayer } from '../render/cap-layer.ts';
import type { MeasurePanel } from './ui/measure-panel.ts';
import type { SurfaceSet } from './surfaces/surface-set.ts';
import type { Spacing, SpacingControl } from './ui/spacing-control.ts';
import { StatsPanel, volumeRows } from './ui/stats-panel.ts';
import type { ViewLink } from './view-link.ts';
import { RayGuidance } from './ray-guidance.ts';

export interface SessionParts {
  viewer: Viewer;
  surface: SurfaceLayer;
  /** The selected surface ray cast in the block cache, when the page draws rays (drawMode). */
  rays: () => RayLayer;
  drawMode: () => 'mesh' | 'rays';
  box: BoxLayer;
  isoControl: IsoControl;
  spacing: SpacingControl;
  stats: StatsPanel;
  budget: BudgetControl;
  hud: Hud;
  bench: BenchPanel;
  link: ViewLink;
  messages: Messages;
  state: PageState;
  volumeInfo: HTMLElement;
  measure: MeasurePanel;
  /** The volume's surfaces (the selected one is `surface`'s). */
  surfaces: SurfaceSet;
  clip: ClipControl;
  caps: () => CapLayer;
  /** The Caps checkbox. */
  capsOn: () => boolean;
}

export class Session {
  current: LoadedVolume | undefined;
  /** Camera to restore on the first volume (from the link the page was opened with). */
  pendingCamera: CameraState | undefined;
  /** Voxel size to use for the first volume instead of the file's (from the link). */
  pendingSpacing: Spacing | undefined;
  /** The clip for the first volume (from the link, or what was on screen before a lost device). */
  pendingClip: Clip | undefined;
  /** The clip on screen (exports and measurements cut the mesh the same way). */
  clip: Clip | undefined;
  private requestedAt = new Map<number, number>();
  /** The isovalue last submitted to the volume's pipeline: its cache holds every block active at it (what rays read). */
  private submittedIso = Number.NaN;
  private lastLatency: number | undefined;
  /** A store's rays read back to refine where they found the surface. */
  private readonly guidance: RayGuidance;

  constructor(private readonly p: SessionParts) {
    this.guidance = new RayGuidance(p.viewer, p.rays);
    p.viewer.addBeforeFrame(() => {
      p.surface.setDrawData(this.current?.iso.drawData);
      p.surfaces.beforeFrame();
      // the caps: inside the outermost visible surface, placed as the surfaces, coloured over the volume's values
      const caps = p.caps();
      const shown = p.surfaces.entries.filter((e) => e.visible && Number.isFinite(e.iso));
      caps.visible = p.capsOn() && shown.length > 0;
      caps.threshold = Math.min(...shown.map((e) => e.iso));
      caps.voxelSize = p.surface.voxelSize;
      caps.origin = p.surface.origin;
      if (this.current) caps.range = this.current.iso.info.valueRange;
      p.surface.setParts(this.current?.iso.drawParts?.());
      this.syncRays();
    });
  }

  /**
   * Rays instead of the selected surface's triangles (the others stay
   * meshes), opaque (see-through rays are not peeled yet): a volume opened
   * whole at the isovalue last submitted (what the cache was computed for);
   * a store's step on screen over its levels' pools and caches, once they
   * hold it (StoreIsosurface.rayLevels: while the next step computes, its
   * mesh copies are drawn, so no frame is empty).
   */
  private syncRays(): void {
    const { p } = this;
    const rays = p.rays();
    const v = this.current;
    const wanted = p.drawMode() === 'rays' && p.surface.style.opacity >= 1;
    v?.iso.setRaysWanted?.(wanted);
    const store = wanted && v?.iso.rayLevels ? v.iso.rayLevels() : undefined;
    const data = wanted && v && !v.iso.drawParts ? v.iso.drawData : undefined;
    const on = store !== undefined || data?.neighbourhoodRanges !== undefined;
    rays.visible = on && p.surface.visible;
    p.state.raysDrawn = rays.visible;
    p.state.raysGuided = this.guidance.asked;
    if (!on) {
      rays.setDrawData(undefined);
      this.guidance.cancel();
      p.state.raysGuiding = false;
      return;
    }
    if (store) {
      rays.setLevels(store.levels, store.extent, store.regions);
      rays.iso = store.iso;
    } else {
      rays.setDrawData(data);
      rays.iso = this.submittedIso;
    }
    rays.style = p.surface.style;
    rays.voxelSize = p.surface.voxelSize;
    rays.origin = p.surface.origin;
    rays.clip = p.surface.clip;
    p.surface.visible = false;
    // a store's rays refined where they found the surface, once its final step is drawn
    if (store && v) this.guidance.drew(v.iso, store, p.surface.voxelSize, p.surface.origin);
    else this.guidance.cancel();
    p.state.raysGuiding = this.guidance.pending;
  }

  install(v: LoadedVolume): void {
    const { p } = this;
    // the volume arrives with its first surface computed (at initialIso); later ones are heard in onSubmit
    this.submittedIso = v.initialIso;
    const old = this.current;
    this.current = v;
    this.requestedAt.clear();
    if (old !== v) p.measure.clear();
    p.surfaces.install(v, v.initialIso);
    // a new volume starts uncut, unless the link (or a lost device's page) gave a clip that meets it
    p.clip.setVolume(v.iso.info.dims, this.pendingClip);
    this.pendingClip = undefined;
    const { info } = v.iso;
    v.iso.onStats((s) => {
      if (this.current === v) this.showStats(s);
    });
    // The draw reads GPU-written arguments: the frame after the submission
    // shows the new surface; the statistics only update the panel.
    v.iso.onSubmit((iso) => {
      if (this.current !== v) return;
      this.submittedIso = iso;
      p.viewer.requestFrame();
    });
    v.iso.onError((e) => {
      if (this.current !== v) return;
      if (e instanceof IsosurfaceBudgetError) {
        p.budget.showError(e);
        p.messages.show(
          `The surface at isovalue ${p.state.iso !== undefined ? Number(p.state.iso.toPrecision(6)) : ''} needs ${formatBytes(e.neededBytes)} of GPU memory for its block cache and vertices; ` +
            `the budget is ${formatBytes(e.budgetBytes)}. The previous surface stays: raise the budget under “Cache and memory”.`,
        );
      } else p.messages.show(`Isosurface: ${e.message}`);
    });
    p.spacing.setVolume(v.opened.spacing);
    if (this.pendingSpacing) p.spacing.setUserValue(this.pendingSpacing);
    p.link.setSpacing(this.pendingSpacing);
    this.pendingSpacing = undefined;
    p.spacing.setEnabled(true);
    this.applySpacing(v, p.spacing.value);
    if (this.pendingCamera) {
      p.viewer.camera.setState(this.pendingCamera);
      this.pendingCamera = undefined;
    }
    const [lo, hi] = info.valueRange;
    p.isoControl.setVolume(info.valueRange, computeBlockProfile(v.ranges, lo, hi), v.initialIso);
    p.isoControl.setEnabled(true);
    setInfoList(p.volumeInfo, volumeRows(v.opened, info.blockCount, info.valueRange));
    p.bench.setVolume(info.valueRange);
    p.budget.clearError();
    p.link.setIso(v.initialIso);
    p.state.volume = {
      name: v.opened.name,
      fileName: v.opened.fileName,
      kind: v.opened.kind,
      dims: info.dims,
      rate: v.opened.rate,
      valueRange: info.valueRange,
      blockCount: info.blockCount,
      spacing: p.spacing.value,
    };
    p.state.iso = v.initialIso;
    p.surface.setDrawData(v.iso.drawData);
    this.lastLatency = undefined;
    this.showStats(v.firstStats);
    p.state.loads++;
    document.title = `${v.opened.name} — ZFP isosurfaces`;
    if (old) {
      old.iso.destroy();
      old.opened.stream.destroy();
    }
    p.viewer.requestFrame();
  }

  /**
   * The volume on screen reaches further than its value range said (a
   * store's provisional range, widened as its bricks report theirs): the
   * slider, its block profile and the panel span the new range; the
   * isovalue stays.
   */
  widenValueRange(v: LoadedVolume, range: [number, number]): void {
    if (this.current !== v) return;
    const { p } = this;
    const info = v.iso.info as { valueRange: [number, number]; blockCount: number };
    info.valueRange = range;
    const [lo, hi] = range;
    p.isoControl.setVolume(range, computeBlockProfile(v.ranges, lo, hi), p.isoControl.value);
    setInfoList(p.volumeInfo, volumeRows(v.opened, info.blockCount, range));
    p.bench.setVolume(range);
    if (p.state.volume) p.state.volume.valueRange = range;
  }

  /** The isovalue of the surface on screen (as the user gave it, else the GPU's float32). */
  get drawnIsovalue(): number | undefined {
    const { state } = this.p;
    if (!this.current || !state.stats) return undefined;
    return state.iso !== undefined && Math.fround(state.iso) === state.stats.isovalue ? state.iso : state.stats.isovalue;
  }

  /** The user changed the voxel size: the surface keeps its triangles, the world stretches; the view fits it. */
  setSpacing(spacing: Spacing): void {
    const v = this.current;
    if (!v) return;
    this.applySpacing(v, spacing);
    if (this.p.state.volume) this.p.state.volume.spacing = spacing;
    this.p.link.setSpacing(spacing);
    this.p.viewer.requestFrame();
  }

  /** World size of a voxel of the volume on screen (PLY export writes world coordinates). */
  get spacing(): Spacing {
    return this.p.spacing.value;
  }

  /** Voxel (i, j, k) at ((i, j, k) + origin) * spacing: surface, box and the fitted view. */
  private applySpacing(v: LoadedVolume, spacing: Spacing): void {
    const { p } = this;
    p.surface.voxelSize = [...spacing];
    const origin = v.opened.origin ?? [0, 0, 0];
    p.surface.origin = [...origin];
    const min = origin.map((o, a) => o * spacing[a]) as [number, number, number];
    const max = v.iso.info.dims.map((n, a) => (n - 1 + origin[a]) * spacing[a]) as [number, number, number];
    const bounds = { min, max };
    p.box.setBounds(bounds);
    p.viewer.fitTo(bounds);
  }

  /** The user moved the isovalue. */
  setIsovalue(iso: number): void {
    const v = this.current;
    if (!v) return;
    const f = Math.fround(iso);
    this.requestedAt.set(f, performance.now());
    if (this.requestedAt.size > 256) this.requestedAt.delete(this.requestedAt.keys().next().value!);
    this.p.state.iso = iso;
    this.p.link.setIso(iso);
    v.iso.setIsovalue(iso);
  }

  private showStats(s: IsosurfaceStats): void {
    const { p } = this;
    const v = this.current!;
    const t = this.requestedAt.get(Math.fround(s.isovalue));
    if (t !== undefined) {
      this.lastLatency = performance.now() - t;
      this.requestedAt.delete(Math.fround(s.isovalue));
    }
    p.stats.update(s, v.iso.info.blockCount, this.lastLatency);
    // a streamed store's meter is what the page holds on the GPU (the store view sets it)
    if (!v.iso.drawParts) p.budget.setUsed(s.cacheBytes + s.vertexBytes + p.surfaces.copyBytes + p.caps().byteSize);
    p.budget.clearError();
    p.hud.setSurface(formatIso(s.isovalue, v.iso.info.valueRange), s.triangles, s.gpuMs);
    p.state.stats = s;
    p.state.statsCount++;
    p.viewer.requestFrame();
  }

  destroy(): void {
    this.current?.iso.destroy();
    this.current?.opened.stream.destroy();
    this.current = undefined;
  }
}

export { StatsPanel };
