// A streamed store as the page's isosurface (PageIsosurface): one volume on
// screen (level 0's dims and voxel size) drawn as the step the stream shows,
// whichever planner made it (by the view, or level by level): one piece per
// level of the step (SurfaceLayer parts: level L at its scale times the voxel
// size, placed by its OME translation, optionally tinted by level), each
// drawn from the copy its step was shown with. Several surfaces: the step
// also draws the page's other isovalues (setOtherIsovalues), each level's
// copy of its surface at each; every isovalue of the step has its pieces
// (partsAt), so a layer per surface draws the step's own geometry for it and
// nothing a replaced step held. Exports read that step: the
// stream shows no other while they read (StoreStream.readShown). The stream
// owns the GPU side; destroying this only detaches it and tells the store
// view.
import type { IsosurfaceDrawData, IsosurfaceStats, SurfaceMesh, VolumeInfo } from '../../isosurface/types.ts';
import type { Rgb, SurfacePart } from '../../render/surface-layer.ts';
import type { ChunkStoreStream } from '../../store/gpu-port.ts';
import { isoIndexOf, joinLevelMeshes, levelsAt, sumStats } from '../../store/stream-surface.ts';
import type { ShownCut } from '../../store/stream/store-stream.ts';
import type { Isosurface } from '../../isosurface/isosurface.ts';
import type { ChunkedVolume } from '../../zfp/chunked-volume.ts';
import type { VolumeProbe } from '../../zfp/probe.ts';
import type { Clip } from '../../core/clip.ts';
import { storeCapPieces } from './store-caps.ts';
import type { CapPiece } from '../../render/cap-layer.ts';
import { type RayRegions, rayLevelsOf } from '../../render/ray-layer.ts';
import { regionOwners } from '../../store/view/regions.ts';
import { MAX_GUIDED_PASSES, seenChunks } from '../../store/view/seen.ts';
import { shownValueAt, type ShownValue } from '../../store/shown-value.ts';
import type { PageIsosurface, PageRayLevels } from '../engine.ts';

export type ShownStep = ShownCut<ChunkedVolume, IsosurfaceStats, Isosurface>;

/** The level tint: level 0 keeps the surface's colour; coarser levels shift toward blue, green, orange, violet. */
export const LEVEL_TINTS: readonly Rgb[] = [
  [1, 1, 1],
  [0.45, 0.7, 1.35],
  [0.55, 1.3, 0.6],
  [1.4, 0.85, 0.45],
  [1.15, 0.55, 1.3],
  [0.6, 1.2, 1.2],
];

export class StoreIsosurface implements PageIsosurface {
  readonly info: VolumeInfo;
  #tint = false;
  /** The pieces drawn, made when the step or the tint changes (the layer asks every frame): the step's own isovalue's. */
  #parts: SurfacePart[] = [];
  /** Per isovalue of the step (its own and its others), its pieces. */
  #partsByIso = new Map<number, SurfacePart[]>();
  /** The isovalue the page asked for last (the selected surface), and what its layer drew last. */
  #wanted = Number.NaN;
  #liveParts: SurfacePart[] = [];
  /** The other isovalues each step draws (several surfaces). */
  #others: readonly number[] = [];
  #stats = new Set<(s: IsosurfaceStats) => void>();
  #errors = new Set<(e: Error) => void>();
  #submits = new Set<(iso: number) => void>();
  #detach: (() => void)[] = [];
  #destroyed = false;
  #shown: ShownStep;
  /** The region grid of the step on screen (rayLevels). */
  #regions: { leaves: unknown; regions: RayRegions } | undefined;
  /** Refinements asked for by the rays since the stream last forgot what they saw (a new camera or isovalue). */
  #guidedPasses = 0;

  constructor(
    private readonly stream: ChunkStoreStream,
    shown: ShownStep,
    valueRange: [number, number],
    /** A new isovalue for the store, with the others drawn with it (newest wins). */
    private readonly request: (iso: number, others: readonly number[]) => Promise<void>,
    /** Refines for what the rays saw (StoreStream.setSeen; null: the view's cut again), as a refinement of the page's (its line and `done`). */
    private readonly requestSeen: (seen: Uint32Array | null) => Promise<void>,
    /** Called once, when the session lets the store go. */
    private readonly onRelease: () => void,
  ) {
    this.#shown = shown;
    this.#others = [...shown.others];
    this.#wanted = shown.iso;
    this.#makeParts();
    const { dims } = stream.levels[0].layout;
    const blockGrid = dims.map((n) => Math.ceil(n / 4)) as [number, number, number];
    this.info = { dims: [...dims], blockGrid, blockCount: blockGrid[0] * blockGrid[1] * blockGrid[2], valueRange };
    this.#detach.push(
      stream.onError((e) => {
        for (const l of this.#errors) l(e);
      }),
    );
  }

  /** The stream showed another step (a new isovalue, a new view, a finer step): statistics, and a frame. */
  showAgain(s: ShownStep): void {
    this.#shown = s;
    this.#makeParts();
    const stats = this.stats;
    for (const l of this.#stats) l(stats);
    for (const l of this.#submits) l(s.iso);
  }

  get shown(): ShownStep {
    return this.#shown;
  }

  get stats(): IsosurfaceStats {
    return sumStats(
      this.#shown.iso,
      this.#shown.levels.map((l) => l.stats),
    );
  }

  /** The finest level's drawn copy (what a single draw would take; none when the step holds no surface); the layer draws drawParts. */
  get drawData(): IsosurfaceDrawData | undefined {
    return this.drawParts()[0]?.data;
  }

  /** The other isovalues every step draws from now on (the next setIsovalue plans for them all). */
  setOtherIsovalues(isos: readonly number[]): void {
    this.#others = [...isos];
  }

  /** The pieces of the step on screen at `iso` (its own isovalue or one of its others); none when it has no such surface. */
  partsAt(iso: number): SurfacePart[] | undefined {
    return this.#partsByIso.get(iso);
  }

  /** Triangles of the step on screen at `iso`, or undefined. */
  trianglesAt(iso: number): number | undefined {
    const k = isoIndexOf(this.#shown, iso);
    if (k === undefined) return undefined;
    return this.#shown.levels.reduce((a, l) => a + (k < 0 ? l.stats : l.others[k].stats).triangles, 0);
  }

  /** Tint the surface by level (the panel's toggle). */
  get tint(): boolean {
    return this.#tint;
  }
  set tint(on: boolean) {
    this.#tint = on;
    this.#makeParts();
  }

  /**
   * The selected surface's pieces: the step's at the isovalue asked for; while
   * a step at a new isovalue is on its way, what was drawn for it last.
   */
  drawParts(): SurfacePart[] {
    const p = this.#partsByIso.get(this.#wanted);
    if (p) this.#liveParts = p;
    return this.#liveParts;
  }

  /** Where each piece is drawn: level, scale (level-0 voxels per voxel) and origin (in its own voxels). */
  get placement(): { level: number; scale: [number, number, number]; origin: [number, number, number] }[] {
    return this.#shown.levels.map((l, i) => ({
      level: l.level,
      scale: [...this.#parts[i].scale] as [number, number, number],
      origin: [...this.#parts[i].origin] as [number, number, number],
    }));
  }

  /**
   * The step on screen for the ray caster (render/ray-layer.ts): each
   * level's pool and live block cache, at the step's own isovalue. None
   * while those caches do not hold the step (StoreStream.cachesShown: a
   * step being computed, caches emptied or released): the step's mesh
   * copies are drawn meanwhile, so no frame is empty.
   */
  rayLevels(): PageRayLevels | undefined {
    const s = this.#shown;
    // the stream's step on screen (a camera move that keeps its plan renews the object, not its levels)
    if (!this.stream.cachesShown || s.levels !== this.stream.shown?.levels) return undefined;
    const { levelOffsets, levelScales } = this.stream.store;
    const levels = rayLevelsOf(
      s.levels,
      levelScales,
      levelOffsets,
      this.#parts.map((p) => p.tint),
    );
    // made once per step (the rays upload it when it changes)
    if (this.#regions?.leaves !== s.leaves)
      this.#regions = {
        leaves: s.leaves,
        regions: regionOwners(
          s.leaves,
          this.stream.levels.map((l) => l.layout),
          levelScales,
        ) ?? { grid: [0, 0, 0], edge: [1, 1, 1], owner: new Uint8Array(0) },
      };
    const { regions } = this.#regions;
    return { levels, extent: this.stream.levels[0].layout.dims, iso: s.iso, regions, final: s.final, step: s.levels };
  }

  /** Whether the page draws rays (rayLevels): the stream then keeps the step on screen's caches whole (StoreStream.setKeepCaches). */
  setRaysWanted(on: boolean): void {
    if (this.#destroyed) return;
    this.stream.setKeepCaches(on);
    // a cut for rays is nested (coarse chunks drawn under finer ones): triangles go back to the view's cut
    if (!on && this.stream.seen) void this.requestSeen(null);
  }

  /**
   * Where the rays of an image of the final step on screen found the surface
   * (hitsFromDepth): their level-0 chunks, with those seen since the last
   * camera or isovalue, go to the stream, which refines there (a cut for
   * rays), at most MAX_GUIDED_PASSES times per view. Whether it asked.
   */
  guideRays(seenHits: { hits: Float64Array; dirs: Float64Array }): boolean {
    const { stream } = this;
    // the step the rays drew, still on screen, with its region grid
    const drawn = this.#destroyed ? undefined : this.rayLevels();
    if (!drawn?.final) return false;
    if (!stream.seen) this.#guidedPasses = 0;
    if (this.#guidedPasses >= MAX_GUIDED_PASSES) return false;
    const regions = drawn.regions.owner.length > 0 ? drawn.regions : null;
    const next = seenChunks(
      seenHits.hits,
      seenHits.dirs,
      stream.levels[0].layout,
      regions,
      stream.store.levelScales,
      stream.seen ?? undefined,
    );
    if (next.added === 0) return false;
    this.#guidedPasses++;
    void this.requestSeen(next.seen);
    return true;
  }

  /** The step's pieces at each of its isovalues (a replaced step's copies are gone: nothing keeps them). */
  #makeParts(): void {
    const { levelOffsets, levelScales } = this.stream.store;
    const s = this.#shown;
    const at = (k: number): SurfacePart[] =>
      s.levels.map((l) => {
        const scale = levelScales[l.level] ?? [2 ** l.level, 2 ** l.level, 2 ** l.level];
        const off = levelOffsets[l.level] ?? [0, 0, 0];
        return {
          // the copy the step was shown with (the surface itself may be computing the next step, or be released)
          data: k < 0 ? (l.surface.presented ?? l.surface.drawData) : l.others[k].copy.drawData,
          scale,
          origin: [off[0] / scale[0], off[1] / scale[1], off[2] / scale[2]],
          ...(this.#tint ? { tint: LEVEL_TINTS[l.level % LEVEL_TINTS.length] } : {}),
        };
      });
    this.#parts = at(-1);
    this.#partsByIso = new Map([[s.iso, this.#parts]]);
    s.others.forEach((iso, k) => this.#partsByIso.set(iso, at(k)));
    // what the selected surface's layer drew may have been a replaced step's copy
    this.#liveParts = this.#partsByIso.get(this.#wanted) ?? this.#parts;
  }

  setIsovalue(iso: number): void {
    this.#wanted = iso;
    void this.request(iso, this.#others);
  }

  /** The surface at `iso` refined to the end of its plan (the in-page benchmark). */
  async compute(iso: number): Promise<IsosurfaceStats> {
    this.#wanted = iso;
    await this.request(iso, this.#others);
    const s = this.stream.shown;
    if (!s || s.iso !== iso) throw new Error(`the store shows no surface at isovalue ${iso}`);
    return sumStats(
      iso,
      s.levels.map((l) => l.stats),
    );
  }

  onStats(l: (s: IsosurfaceStats) => void): () => void {
    this.#stats.add(l);
    return () => this.#stats.delete(l);
  }
  onError(l: (e: Error) => void): () => void {
    this.#errors.add(l);
    return () => this.#errors.delete(l);
  }
  onSubmit(l: (iso: number) => void): () => void {
    this.#submits.add(l);
    return () => this.#submits.delete(l);
  }

  resetCache(): void {
    if (this.#shown.frozen) return;
    for (const l of this.#shown.levels) l.surface.resetCache();
  }

  /** The page's budget object holds every store's limit (main.ts sets it): nothing to do per surface. */
  setMemoryBudget(): void {}

  /** The finest level's drawn mesh in its own voxels (callers that can, use readPositions: every level, in level-0 voxels). */
  async readMesh(): Promise<SurfaceMesh> {
    const mesh = await this.stream.readShown((s) => s.levels[0]?.surface.readDrawnMesh() ?? Promise.resolve(null));
    return mesh ?? { vertices: new Uint32Array(0), indices: new Uint32Array(0), dims: [...this.info.dims] };
  }

  /**
   * The step on screen, every level's mesh as one in level-0 voxel index
   * space (the PLY export), at `iso` (default: the selected surface's); the
   * stream shows no other step meanwhile.
   */
  async readPositions(iso = this.#wanted): Promise<{ positions: Float32Array; indices: Uint32Array }> {
    const { levelOffsets, levelScales } = this.stream.store;
    const read = await this.stream.readShown((s) =>
      joinLevelMeshes(levelsAt(this.stream, s, isoIndexOf(s, iso) ?? -1), levelOffsets, levelScales),
    );
    return read ?? { positions: new Float32Array(0), indices: new Uint32Array(0) };
  }

  /** The value at `p` (level-0 voxels) of the step on screen, from the finest level holding it (a picked point); the stream shows no other step meanwhile. */
  async valueAt(p: readonly [number, number, number], probe: VolumeProbe): Promise<ShownValue | null> {
    const { levelOffsets, levelScales } = this.stream.store;
    return this.stream.readShown((s) => shownValueAt(probe, s, levelOffsets, levelScales, p));
  }

  /** The caps of `clip` on the step on screen (store-caps.ts); none once the step was released to its copies. */
  capPieces(clip: Clip): CapPiece[] {
    return storeCapPieces(this.stream.store, this.#shown, clip);
  }

  /** The coarsest level's block ranges (the slider's block profile); none once the step was released to its copies. */
  readBlockRanges(): Promise<Float32Array> {
    const coarsest = this.#shown.levels.at(-1);
    return coarsest && !this.#shown.frozen ? coarsest.surface.readBlockRanges() : Promise.resolve(new Float32Array(0));
  }

  destroy(): void {
    if (this.#destroyed) return;
    this.#destroyed = true;
    for (const d of this.#detach) d();
    this.#stats.clear();
    this.#errors.clear();
    this.#submits.clear();
    this.onRelease();
  }
}
