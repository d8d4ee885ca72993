// A store's surface as the page's isosurface (PageIsosurface): what the
// session draws and scrubs is the level stream's shown level. One of
// these per level installed; the stream owns the GPU side (pools and
// surfaces), so destroying this one only detaches it, unless the store view
// says the store itself is gone (another volume replaced it).
import type { Isosurface } from '../../isosurface/isosurface.ts';
import type { IsosurfaceDrawData, IsosurfaceStats, SurfaceMesh, VolumeInfo } from '../../isosurface/types.ts';
import type { ChunkLevelStream } from '../../store/pinned-level.ts';
import type { ShownSurface } from '../../store/stream-port.ts';
import type { ChunkedVolume } from '../../zfp/chunked-volume.ts';
import type { PageIsosurface } from '../engine.ts';

export type ShownLevel = ShownSurface<ChunkedVolume, IsosurfaceStats, Isosurface>;

export class StoreLevelIsosurface implements PageIsosurface {
  readonly info: VolumeInfo;
  #stats = new Set<(s: IsosurfaceStats) => void>();
  #errors = new Set<(e: Error) => void>();
  #submits = new Set<(iso: number) => void>();
  #detach: (() => void)[] = [];
  #destroyed = false;

  constructor(
    private readonly controller: ChunkLevelStream,
    private shown: ShownLevel,
    valueRange: [number, number],
    /** A new isovalue for the store (the store view's refinement: newest wins, stale requests aborted). */
    private readonly request: (iso: number) => Promise<void>,
    /** Called once, when the session lets this level go. */
    private readonly onRelease: () => void,
    /** The user changed the GPU memory budget (the store view gives it to the controller). */
    private readonly onBudget: (bytes: number) => void = () => {},
  ) {
    // the level's blocks (the surface's own count is its pool's block ids: what is resident)
    const { dims } = shown.volume.layout;
    const blockGrid = dims.map((n) => Math.ceil(n / 4)) as [number, number, number];
    this.info = { dims: [...dims], blockGrid, blockCount: blockGrid[0] * blockGrid[1] * blockGrid[2], valueRange };
    this.#detach.push(
      controller.onError((e) => {
        for (const l of this.#errors) l(e);
      }),
      shown.surface.onSubmit((iso) => {
        for (const l of this.#submits) l(iso);
      }),
    );
  }

  get level(): number {
    return this.shown.level;
  }

  /** The controller showed this level again (a new isovalue at the same level). */
  showAgain(s: ShownLevel): void {
    this.shown = s;
    for (const l of this.#stats) l(s.stats);
  }

  get drawData(): IsosurfaceDrawData {
    return this.shown.surface.drawData;
  }

  /** Newest wins: the controller aborts what the previous isovalue still fetched and no longer needs. */
  setIsovalue(iso: number): void {
    void this.request(iso);
  }

  /** The surface at `iso`, at the finest level the store view allows (the in-page benchmark). */
  async compute(iso: number): Promise<IsosurfaceStats> {
    await this.request(iso);
    const s = this.controller.shown;
    if (!s || s.iso !== iso) throw new Error(`the store shows no surface at isovalue ${iso}`);
    return s.stats;
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
    this.shown.surface.resetCache();
  }

  /** The whole store's budget (pools, surfaces, everything): applies from the next step of the refinement on. */
  setMemoryBudget(bytes: number): void {
    this.onBudget(bytes);
  }

  readMesh(): Promise<SurfaceMesh> {
    return this.shown.surface.readMesh();
  }

  readBlockRanges(): Promise<Float32Array> {
    return this.shown.surface.readBlockRanges();
  }

  /** Detaches, then tells the store view (which closes the store unless it is installing another level of it). */
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
