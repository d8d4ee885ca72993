// Several isosurfaces of the volume on screen (up to 8), each with its
// isovalue, colour, opacity and visibility. One pipeline computes them all,
// so they share one block cache (a block is decompressed once for every
// surface that needs it): the selected surface is the one the slider moves,
// computed and drawn live by the page's surface layer; every other surface
// is a GPU copy of its last computation (SurfaceSnapshot), drawn by a layer
// of its own. Moving one surface recomputes only that one. Selecting another
// surface computes the one left once more (from the cache), copies it, and
// makes the chosen one live; until its first computation is submitted the
// chosen one is still drawn from its copy, so no frame shows a wrong surface.
// The copies count against the page's budget: the pipeline's own cap is the
// budget less what the copies hold, and a copy that does not fit is refused.
//
// A store's stream draws every visible surface in each of its steps, from
// the same resident chunks (a chunk is fetched when any of them needs it):
// there the set tells the stream the other isovalues, and each surface but
// the selected one has a layer drawing the step's pieces at its isovalue
// (StoreIsosurface.partsAt). Moving one surface plans the step again for all;
// the stream keeps the copies of the others where the step's chunks did not
// change. Their memory is the stream's: the store's budget counts it.
import { SURFACE_PALETTE } from '../../mc/glb.ts';
import type { SurfaceSnapshot } from '../../isosurface/snapshot.ts';
import { meshPositions } from '../../isosurface/vertex-format.ts';
import type { Rgb, SurfaceLayer } from '../../render/surface-layer.ts';
import type { Viewer } from '../../render/viewer.ts';
import type { LoadedVolume } from '../loading/loader.ts';
import type { Messages } from '../messages.ts';
import type { SurfaceSpec } from '../url-state.ts';

export const MAX_SURFACES = 8;

/** Whether a volume can show several surfaces: copies of its pipeline's (in-core) or several per step (a store's stream). */
const severalOf = (v: LoadedVolume) => v.iso.newCopy !== undefined || v.iso.setOtherIsovalues !== undefined;

export interface SurfaceEntry {
  /** Stable while the entry lives (panel rows, copies). */
  readonly id: number;
  iso: number;
  /** Outside colour, sRGB 0..1. */
  color: Rgb;
  /** 1 opaque; below 1 see-through (depth peeled). */
  opacity: number;
  visible: boolean;
}

interface CopyDraw {
  copy: SurfaceSnapshot;
  layer: SurfaceLayer;
}

export interface SurfaceSetDeps {
  viewer: () => Viewer;
  /** The page's surface layer: draws the selected surface live. */
  live: () => SurfaceLayer;
  /** A layer for one copy (same target as the live one). */
  makeLayer: () => Promise<SurfaceLayer>;
  current: () => LoadedVolume | undefined;
  /** Moves the live surface (the session: statistics, link, latency). */
  setLiveIsovalue: (iso: number) => void;
  /** Shows an isovalue on the slider without moving anything. */
  showIso: (iso: number) => void;
  budgetBytes: () => number;
  messages: Messages;
  /** The entries or the selection changed (panel, link). */
  onChange: () => void;
}

export class SurfaceSet {
  readonly entries: SurfaceEntry[] = [];
  selected = 0;
  #nextId = 1;
  readonly #copies = new Map<number, CopyDraw>();
  /** A store's surfaces but the selected one: a layer each, drawing the step's pieces at its isovalue. */
  readonly #storeLayers = new Map<number, SurfaceLayer>();
  /** The volume the copies were computed from. */
  #volume: LoadedVolume | undefined;
  /** Selection changes run one at a time, in order; while any is on its way the slider's values wait in #pendingIso. */
  #chain: Promise<void> = Promise.resolve();
  #switches = 0;
  #pendingIso: number | undefined;
  /** The surface the latest select() chose (the slider shows it while the change is on its way). */
  #target: SurfaceEntry | undefined;
  /** False from a selection until the chosen surface's first submission: the live layer still holds the surface left. */
  #liveReady = true;

  constructor(private readonly d: SurfaceSetDeps) {
    this.entries.push(this.#entry(Number.NaN, SURFACE_PALETTE[0]));
  }

  get selectedEntry(): SurfaceEntry {
    return this.entries[this.selected];
  }

  /** The surface the slider shows: the selected one, or the one a selection change in progress goes to. */
  get shownEntry(): SurfaceEntry {
    return this.#target ?? this.selectedEntry;
  }

  /** Several surfaces need a pipeline that copies its surfaces (in-core volumes) or a stream that draws several (stores). */
  get canAdd(): boolean {
    const v = this.d.current();
    return v !== undefined && severalOf(v) && this.entries.length < MAX_SURFACES && this.#switches === 0;
  }

  /** Bytes the copies hold. */
  get copyBytes(): number {
    let n = 0;
    for (const c of this.#copies.values()) n += c.copy.byteSize;
    return n;
  }

  /** A new volume is on screen: one surface (the selected one's colour and opacity) at its first isovalue. */
  install(v: LoadedVolume, iso: number): void {
    this.#dropCopies();
    const keep = this.selectedEntry;
    this.entries.length = 0;
    this.entries.push({ ...keep, iso });
    this.selected = 0;
    this.#volume = v;
    this.#liveReady = true;
    this.#pendingIso = undefined;
    v.iso.onSubmit((submitted) => this.#submitted(v, submitted));
    this.d.onChange();
  }

  /**
   * The surfaces of a link: the one on screen (opened at specs[selected].iso)
   * takes that entry's style, the others are computed and copied in turn,
   * then the list takes the link's order and the link's selection.
   */
  async restore(specs: SurfaceSpec[], selected: number): Promise<void> {
    const first = this.selectedEntry;
    const own = specs[selected];
    Object.assign(first, {
      ...(own.color ? { color: [...own.color] } : {}),
      ...(own.opacity !== undefined ? { opacity: own.opacity } : {}),
      visible: own.visible ?? true,
    });
    const order = new Map<SurfaceEntry, number>([[first, selected]]);
    for (let i = 0; i < specs.length; i++) {
      if (i === selected) continue;
      const spec = specs[i];
      if (!(await this.add(spec.iso, { color: spec.color, opacity: spec.opacity, visible: spec.visible }))) return;
      order.set(this.entries[this.entries.length - 1], i);
    }
    const selectedEntry = this.selectedEntry;
    this.entries.sort((a, b) => (order.get(a) ?? 0) - (order.get(b) ?? 0));
    this.selected = this.entries.indexOf(selectedEntry);
    await this.select(this.entries.indexOf(first));
  }

  /** The slider moved: the selected surface follows (after a selection change in progress). */
  setIsovalue(iso: number): void {
    if (this.#switches > 0) {
      (this.#target ?? this.selectedEntry).iso = iso;
      this.#pendingIso = iso;
      this.d.onChange();
      return;
    }
    this.selectedEntry.iso = iso;
    this.#storeOthers();
    this.d.setLiveIsovalue(iso);
    this.d.onChange();
  }

  /** A store: the stream's next step draws every visible surface but the selected one as its others. */
  #storeOthers(): void {
    const v = this.d.current();
    if (!v?.iso.setOtherIsovalues || v !== this.#volume) return;
    const sel = this.selectedEntry;
    v.iso.setOtherIsovalues(this.entries.filter((e) => e !== sel && e.visible && Number.isFinite(e.iso)).map((e) => e.iso));
  }

  /** A store's surfaces changed (one removed, hidden or shown): the step is planned again for them. */
  #replanStore(): void {
    const v = this.d.current();
    if (!v?.iso.setOtherIsovalues || v !== this.#volume || this.#switches > 0) return;
    this.#storeOthers();
    if (Number.isFinite(this.selectedEntry.iso)) this.d.setLiveIsovalue(this.selectedEntry.iso);
  }

  /** Adds a surface at `iso` (default: a tenth of the value range above the selected one) and selects it. */
  async add(iso?: number, style: Partial<Pick<SurfaceEntry, 'color' | 'opacity' | 'visible'>> = {}): Promise<boolean> {
    const v = this.d.current();
    if (!v) return false;
    if (!severalOf(v)) {
      this.d.messages.show('This volume shows one surface.', 'info', 5000);
      return false;
    }
    if (this.entries.length >= MAX_SURFACES) {
      this.d.messages.show(`At most ${MAX_SURFACES} surfaces at once.`, 'info', 4000);
      return false;
    }
    const [lo, hi] = v.iso.info.valueRange;
    const at = iso ?? Math.min(hi, this.selectedEntry.iso + (hi - lo) / 10);
    if (!(at >= lo && at <= hi)) {
      this.d.messages.show(`Isovalue ${at} is outside the volume's values (${lo} … ${hi}): no surface added.`);
      return false;
    }
    const used = new Set(this.entries.map((e) => e.color.join()));
    const color =
      style.color ?? SURFACE_PALETTE.find((c) => !used.has(c.join())) ?? SURFACE_PALETTE[this.entries.length % SURFACE_PALETTE.length];
    const entry = {
      ...this.#entry(at, color),
      ...(style.opacity !== undefined ? { opacity: style.opacity } : {}),
      visible: style.visible ?? true,
    };
    this.entries.push(entry);
    const ok = await this.select(this.entries.length - 1);
    if (!ok) {
      const i = this.entries.indexOf(entry);
      if (i >= 0) this.entries.splice(i, 1);
    }
    this.d.onChange();
    return ok;
  }

  /** Removes a surface (not the last one); the selected one hands the slider to a neighbour first. */
  async remove(index: number): Promise<void> {
    if (this.entries.length <= 1 || index < 0 || index >= this.entries.length) return;
    const entry = this.entries[index];
    if (index === this.selected && !(await this.select(index > 0 ? index - 1 : 1))) return;
    const i = this.entries.indexOf(entry);
    this.entries.splice(i, 1);
    if (i < this.selected) this.selected--;
    this.#dropCopy(entry.id);
    this.#applyBudget();
    this.#replanStore();
    this.d.onChange();
    this.d.viewer().requestFrame();
  }

  /** Moves a surface one place up the list (the order of the panel, the link and the exports). */
  moveUp(index: number): void {
    if (index <= 0 || index >= this.entries.length || this.#switches > 0) return;
    const selectedId = this.selectedEntry.id;
    [this.entries[index - 1], this.entries[index]] = [this.entries[index], this.entries[index - 1]];
    this.selected = this.entries.findIndex((e) => e.id === selectedId);
    this.d.onChange();
  }

  /** Colour, opacity, visibility: drawn at the next frame, nothing recomputed. */
  setStyle(index: number, style: Partial<Pick<SurfaceEntry, 'color' | 'opacity' | 'visible'>>): void {
    const e = this.entries[index];
    if (!e) return;
    const shown = style.visible !== undefined && style.visible !== e.visible;
    Object.assign(e, style);
    // a store computes only the visible surfaces
    if (shown && e !== this.selectedEntry) this.#replanStore();
    this.d.onChange();
    this.d.viewer().requestFrame();
  }

  /** Makes `index` the surface the slider moves; false when the one left could not be kept (budget, GPU). */
  select(index: number): Promise<boolean> {
    const entry = this.entries[index];
    if (!entry) return Promise.resolve(false);
    // the slider shows the chosen surface at once; what it is moved to meanwhile goes to that surface
    this.#target = entry;
    this.#pendingIso = undefined;
    if (Number.isFinite(entry.iso)) this.d.showIso(entry.iso);
    const run = () => this.#switchTo(entry);
    const mine = this.#chain.then(run, run);
    this.#switches++;
    this.#chain = mine.then(
      () => this.#switched(),
      () => this.#switched(),
    );
    this.d.onChange();
    return mine;
  }

  async #switchTo(entry: SurfaceEntry): Promise<boolean> {
    const left = this.selectedEntry;
    if (entry === left) return true;
    const v = this.d.current();
    if (!this.entries.includes(entry) || !v || v !== this.#volume) return false;
    if (v.iso.setOtherIsovalues) return this.#switchStore(v, left, entry);
    if (!v.iso.newCopy || !v.iso.copyInto) return false;
    if (Number.isFinite(left.iso)) {
      // the surface left: computed once more (its blocks are cached) so its copy holds exactly it
      let stats;
      try {
        stats = await v.iso.compute(left.iso);
      } catch (e) {
        this.d.messages.show(`Surface at ${left.iso}: ${(e as Error).message}`);
        return this.#refused();
      }
      if (this.d.current() !== v) return false;
      const needed = stats.vertices * 12 + stats.indices * 4;
      const held = this.copyBytes - (this.#copies.get(left.id)?.copy.byteSize ?? 0);
      if (held + needed + (v.iso.budgetedBytes ?? 0) > this.d.budgetBytes()) {
        this.d.messages.show(
          `Keeping the surface at ${Number(left.iso.toPrecision(6))} as well needs ${(needed / 2 ** 20).toFixed(1)} MiB more than the GPU memory budget holds: raise the budget to show several surfaces.`,
        );
        return this.#refused();
      }
      let draw = this.#copies.get(left.id);
      if (!draw) {
        const layer = await this.d.makeLayer();
        if (this.d.current() !== v) {
          layer.destroy();
          return false;
        }
        draw = { copy: v.iso.newCopy(), layer };
        this.#copies.set(left.id, draw);
        this.d.viewer().addLayer(layer);
      }
      v.iso.copyInto(draw.copy);
      draw.layer.setDrawData(draw.copy.drawData);
    }
    this.selected = this.entries.indexOf(entry);
    this.#liveReady = false;
    this.#applyBudget();
    if (this.#target === entry && this.#pendingIso !== undefined) {
      entry.iso = this.#pendingIso;
      this.#pendingIso = undefined;
    }
    this.d.setLiveIsovalue(entry.iso);
    this.d.onChange();
    return true;
  }

  /**
   * A store: the surface left gets a layer of its own (the step's pieces at
   * its isovalue) and the chosen one is drawn by the live layer; the next
   * step draws the chosen one as its own isovalue and the others with it.
   */
  async #switchStore(v: LoadedVolume, left: SurfaceEntry, entry: SurfaceEntry): Promise<boolean> {
    if (!this.#storeLayers.has(left.id)) {
      const layer = await this.d.makeLayer();
      if (this.d.current() !== v || !this.entries.includes(left)) {
        layer.destroy();
        return false;
      }
      this.#storeLayers.set(left.id, layer);
      this.d.viewer().addLayer(layer);
    }
    this.selected = this.entries.indexOf(entry);
    if (this.#target === entry && this.#pendingIso !== undefined) {
      entry.iso = this.#pendingIso;
      this.#pendingIso = undefined;
    }
    this.#storeOthers();
    if (Number.isFinite(entry.iso)) this.d.setLiveIsovalue(entry.iso);
    this.d.onChange();
    return true;
  }

  /** The selection stays where it was: the slider shows that surface again. */
  #refused(): false {
    this.#target = undefined;
    this.#pendingIso = undefined;
    this.d.showIso(this.selectedEntry.iso);
    this.d.onChange();
    return false;
  }

  /** A selection change ended: slider values that came meanwhile go to the selected surface. */
  #switched(): void {
    if (--this.#switches > 0) return;
    this.#target = undefined;
    if (this.#pendingIso !== undefined) {
      const iso = this.#pendingIso;
      this.#pendingIso = undefined;
      this.selectedEntry.iso = iso;
      this.#storeOthers();
      this.d.setLiveIsovalue(iso);
    }
    this.d.onChange(); // adding and reordering are possible again
  }

  /** Before each frame: styles, visibility and placement of every layer. */
  beforeFrame(): void {
    const live = this.d.live();
    const sel = this.selectedEntry;
    live.style.front = sel.color;
    live.style.opacity = sel.opacity;
    live.visible = sel.visible && this.#liveReady;
    for (const e of this.entries) {
      const draw = this.#copies.get(e.id);
      if (!draw) continue;
      draw.layer.style = { ...live.style, front: e.color, opacity: e.opacity };
      draw.layer.voxelSize = live.voxelSize;
      draw.layer.origin = live.origin;
      if (draw.layer.clip !== live.clip) draw.layer.clip = live.clip;
      // the selected surface's copy shows until the live one has its surface
      draw.layer.visible = e.visible && (e !== sel || !this.#liveReady);
    }
    const v = this.d.current();
    for (const e of this.entries) {
      const layer = this.#storeLayers.get(e.id);
      if (!layer) continue;
      const parts = e !== sel && v === this.#volume ? v?.iso.partsAt?.(e.iso) : undefined;
      layer.style = { ...live.style, front: e.color, opacity: e.opacity };
      layer.voxelSize = live.voxelSize;
      layer.origin = live.origin;
      if (layer.clip !== live.clip) layer.clip = live.clip;
      layer.setParts(parts);
      layer.visible = e.visible && parts !== undefined;
    }
  }

  /** Triangles drawn of a surface now (its copy's, or a store step's at its isovalue); undefined for the live one of an in-core volume. */
  trianglesOf(entry: SurfaceEntry): number | undefined {
    const copy = this.copyOf(entry);
    if (copy) return copy.triangles;
    const v = this.d.current();
    return v?.iso.trianglesAt?.(entry.iso);
  }

  /**
   * Where an export reads a surface that is not the live one: its copy (an
   * in-core volume), or the store's step at its isovalue; undefined: the
   * live surface (readShownMesh's default).
   */
  meshOf(entry: SurfaceEntry): { iso: number; read: () => Promise<{ positions: Float32Array; indices: Uint32Array }> } | undefined {
    const copy = this.copyOf(entry);
    const v = this.d.current();
    if (copy) {
      const dims = v?.iso.info.dims ?? [0, 0, 0];
      return {
        iso: entry.iso,
        read: async () => {
          const mesh = await copy.readMesh(dims);
          return { positions: meshPositions(mesh), indices: mesh.indices };
        },
      };
    }
    if (v?.iso.partsAt && entry !== this.selectedEntry && v.iso.readPositions) {
      const read = v.iso.readPositions.bind(v.iso);
      return { iso: entry.iso, read: () => read(entry.iso) };
    }
    return undefined;
  }

  /** Every surface's copy (not the selected one's, which is live): for exports. */
  copyOf(entry: SurfaceEntry): SurfaceSnapshot | undefined {
    return entry === this.selectedEntry && this.#liveReady ? undefined : this.#copies.get(entry.id)?.copy;
  }

  /** The link's surfaces. */
  specs(): SurfaceSpec[] {
    return this.entries.map((e) => ({ iso: e.iso, color: e.color, opacity: e.opacity, visible: e.visible }));
  }

  #submitted(v: LoadedVolume, iso: number): void {
    if (v !== this.#volume || this.#liveReady) return;
    if (Math.fround(iso) !== Math.fround(this.selectedEntry.iso)) return;
    this.#liveReady = true;
    // the chosen surface is live now: its copy goes (memory back to the pipeline)
    this.#dropCopy(this.selectedEntry.id);
    this.#applyBudget();
    this.d.viewer().requestFrame();
  }

  /** Whether a surface is kept drawn: the selected one, one whose copy is kept, or any of a store's (its steps draw them all). */
  isDrawn(entry: SurfaceEntry): boolean {
    return entry === this.selectedEntry || this.#copies.has(entry.id) || this.d.current()?.iso.setOtherIsovalues !== undefined;
  }

  /**
   * A lowered budget: copies go, largest first, until the copies and the
   * pipeline fit it (their surfaces stay in the list, undrawn; selecting one
   * computes it again). The isovalues let go, for the message.
   */
  fitBudget(): number[] {
    const v = this.d.current();
    const dropped: number[] = [];
    if (v && v === this.#volume) {
      const budget = this.d.budgetBytes();
      const pipeline = v.iso.budgetedBytes ?? 0;
      while (this.#copies.size > 0 && this.copyBytes + pipeline > budget) {
        let largest: [number, CopyDraw] | undefined;
        for (const c of this.#copies) if (!largest || c[1].copy.byteSize > largest[1].copy.byteSize) largest = c;
        const entry = this.entries.find((e) => e.id === largest![0]);
        if (entry) dropped.push(entry.iso);
        this.#dropCopy(largest![0]);
      }
    }
    this.#applyBudget();
    if (dropped.length > 0) this.d.onChange();
    return dropped;
  }

  /** The pipeline's cap: the page's budget less what the copies hold. */
  #applyBudget(): void {
    const v = this.d.current();
    if (!v || v !== this.#volume) return;
    v.iso.setMemoryBudget(Math.max(1, this.d.budgetBytes() - this.copyBytes));
  }

  #entry(iso: number, color: readonly [number, number, number]): SurfaceEntry {
    return { id: this.#nextId++, iso, color: [...color] as Rgb, opacity: 1, visible: true };
  }

  #dropCopy(id: number): void {
    const layer = this.#storeLayers.get(id);
    if (layer) {
      this.d.viewer().removeLayer(layer);
      layer.destroy();
      this.#storeLayers.delete(id);
    }
    const draw = this.#copies.get(id);
    if (!draw) return;
    this.d.viewer().removeLayer(draw.layer);
    draw.layer.destroy();
    draw.copy.destroy();
    this.#copies.delete(id);
  }

  #dropCopies(): void {
    for (const id of [...this.#copies.keys(), ...this.#storeLayers.keys()]) this.#dropCopy(id);
  }

  destroy(): void {
    this.#dropCopies();
  }
}
