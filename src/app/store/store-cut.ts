// A store refined by the view as the page's isosurface (PageIsosurface):
// one volume on screen (level 0's dims and voxel size) drawn as several
// pieces, one per level of the cut (SurfaceLayer parts: level L at 2^L times
// the voxel size, placed by its OME translation, optionally tinted by
// level). The view stream owns the GPU side; destroying this only detaches
// it and tells the store view.
import type { IsosurfaceDrawData, IsosurfaceStats, SurfaceMesh, VolumeInfo } from '../../isosurface/types.ts';
import type { Rgb, SurfacePart } from '../../render/surface-layer.ts';
import type { ShownCut } from '../../store/stream/store-stream.ts';
import type { ChunkStoreStream } from '../../store/gpu-port.ts';
import { joinLevelMeshes, sumStats } from '../../store/view-surface.ts';
import type { Isosurface } from '../../isosurface/isosurface.ts';
import type { ChunkedVolume } from '../../zfp/chunked-volume.ts';
import type { PageIsosurface } from '../engine.ts';

export type ShownCutOfPage = ShownCut<ChunkedVolume, IsosurfaceStats, Isosurface>;

/** The level tint: level 0 keeps the surface's colour; coarser levels shift toward blue, green, orange, violet. */
export const LEVEL_TINTS: readonly Rgb[] = [
  [1, 1, 1],
  [0.45, 0.7, 1.35],
  [0.55, 1.3, 0.6],
  [1.4, 0.85, 0.45],
  [1.15, 0.55, 1.3],
  [0.6, 1.2, 1.2],
];

export class StoreCutIsosurface implements PageIsosurface {
  readonly info: VolumeInfo;
  #tint = false;
  /** The pieces drawn, made when the shown cut or the tint changes (the layer asks every frame). */
  #parts: SurfacePart[] = [];
  #stats = new Set<(s: IsosurfaceStats) => void>();
  #errors = new Set<(e: Error) => void>();
  #submits = new Set<(iso: number) => void>();
  #detach: (() => void)[] = [];
  #destroyed = false;
  #shown: ShownCutOfPage;

  constructor(
    private readonly stream: ChunkStoreStream,
    shown: ShownCutOfPage,
    valueRange: [number, number],
    /** A new isovalue for the store (newest wins). */
    private readonly request: (iso: number) => Promise<void>,
    /** Called once, when the session lets the store go. */
    private readonly onRelease: () => void,
    private readonly onBudget: (bytes: number) => void = () => {},
  ) {
    this.#shown = shown;
    this.#parts = this.#makeParts();
    const { dims } = stream.levels[0].layout;
    const blockGrid = dims.map((n) => Math.ceil(n / 4)) as [number, number, number];
    this.info = { dims: [...dims], blockGrid, blockCount: blockGrid[0] * blockGrid[1] * blockGrid[2], valueRange };
    this.#detach.push(
      stream.onError((e) => {
        for (const l of this.#errors) l(e);
      }),
    );
  }

  /** The view stream showed another step (a new isovalue, a new view, a finer step): statistics, and a frame. */
  showAgain(s: ShownCutOfPage): void {
    this.#shown = s;
    this.#parts = this.#makeParts();
    const stats = this.stats;
    for (const l of this.#stats) l(stats);
    for (const l of this.#submits) l(s.iso);
  }

  get shown(): ShownCutOfPage {
    return this.#shown;
  }

  get stats(): IsosurfaceStats {
    return sumStats(
      this.#shown.iso,
      this.#shown.levels.map((l) => l.stats),
    );
  }

  /** The finest level's surface (what a single draw would take; none when the cut holds no surface); the layer draws drawParts. */
  get drawData(): IsosurfaceDrawData | undefined {
    const finest = this.#shown.levels[0]?.surface;
    return finest ? (finest.presented ?? finest.drawData) : undefined;
  }

  /** Tint the surface by level (the panel's toggle). */
  get tint(): boolean {
    return this.#tint;
  }
  set tint(on: boolean) {
    this.#tint = on;
    this.#parts = this.#makeParts();
  }

  drawParts(): SurfacePart[] {
    return this.#parts;
  }

  #makeParts(): SurfacePart[] {
    const offsets = this.stream.store.levelOffsets;
    return this.#shown.levels.map((l) => {
      const k = this.stream.store.levelScales[l.level] ?? [2 ** l.level, 2 ** l.level, 2 ** l.level];
      const off = offsets[l.level] ?? [0, 0, 0];
      return {
        // the copy the step was shown with (a snapshot: the surface itself may be computing the next step)
        data: l.surface.presented ?? l.surface.drawData,
        scale: k,
        origin: [off[0] / k[0], off[1] / k[1], off[2] / k[2]],
        ...(this.#tint ? { tint: LEVEL_TINTS[l.level % LEVEL_TINTS.length] } : {}),
      };
    });
  }

  setIsovalue(iso: number): void {
    void this.request(iso);
  }

  async compute(iso: number): Promise<IsosurfaceStats> {
    await this.request(iso);
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
    for (const l of this.#shown.levels) l.surface.resetCache();
  }

  setMemoryBudget(bytes: number): void {
    this.onBudget(bytes);
  }

  /** The finest level's mesh in its own voxels (callers that can, use readPositions: every level, in level-0 voxels). */
  readMesh(): Promise<SurfaceMesh> {
    const finest = this.#shown.levels[0];
    // an empty cut (no chunk in view holds the isovalue): no triangles
    return finest
      ? finest.surface.readMesh()
      : Promise.resolve({ vertices: new Uint32Array(0), indices: new Uint32Array(0), dims: [...this.info.dims] });
  }

  /** Every level's mesh as one, in level-0 voxel index space (the PLY export). */
  readPositions(): Promise<{ positions: Float32Array; indices: Uint32Array }> {
    return joinLevelMeshes(this.#shown.levels, this.stream.store.levelOffsets, this.stream.store.levelScales);
  }

  /** The coarsest level's block ranges (the slider's block profile). */
  readBlockRanges(): Promise<Float32Array> {
    const coarsest = this.#shown.levels.at(-1);
    return coarsest ? coarsest.surface.readBlockRanges() : Promise.resolve(new Float32Array(0));
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
