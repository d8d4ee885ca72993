// One level of a store as one surface for the CLI (`extract` / `bench`
// STORE --level L): the level stream pinned to level L, so each
// isovalue fetches only the chunks its surface needs at that level (plan.ts)
// into the level's pool of compressed chunks, then computes the surface with
// the one isosurface pipeline over that pool. What `extract` and `bench`
// read of an Isosurface (info, compute, readMesh, resetCache,
// memoryBudget), with the store's figures for their records.
import type { Isosurface } from '../isosurface/isosurface.ts';
import type { IsosurfaceStats, SurfaceMesh, VolumeInfo } from '../isosurface/types.ts';
import type { ChunkedVolume } from '../zfp/chunked-volume.ts';
import type { LevelStream } from './stream/level-stream.ts';

/** The level could not show a surface at this isovalue (over the budget, a failed chunk): the stream's reason. */
export class LevelStoppedError extends Error {
  constructor(
    message: string,
    /** True when the reason is the memory budget (not a failed chunk or a GPU error). */
    readonly overBudget = false,
  ) {
    super(message);
    this.name = 'LevelStoppedError';
  }
}

export type ChunkLevelStream = LevelStream<ChunkedVolume, IsosurfaceStats, Isosurface>;

export class PinnedLevelSurface {
  readonly info: VolumeInfo;
  #reason: string | null = null;
  #overBudget = false;
  #errors: string[] = [];

  constructor(
    readonly levels: ChunkLevelStream,
    readonly level: number,
  ) {
    levels.finest = level;
    levels.coarsest = level;
    const { dims } = levels.levels[level].layout;
    const blockGrid = dims.map((n) => Math.ceil(n / 4)) as [number, number, number];
    this.info = {
      dims: [...dims],
      blockGrid,
      blockCount: blockGrid[0] * blockGrid[1] * blockGrid[2],
      valueRange: levels.valueRange ?? [0, 0],
    };
    levels.onProgress((p) => {
      if (p.phase === 'stopped') {
        this.#reason = p.reason ?? `level ${level} stopped`;
        this.#overBudget = p.cause === 'budget';
      }
    });
    levels.onError((e) => this.#errors.push(e.message));
  }

  /** Messages of chunks that failed (after their retries), in order. */
  get errors(): readonly string[] {
    return this.#errors;
  }

  get memoryBudget(): number {
    return this.levels.budgetBytes;
  }

  /** Fetches what the surface at `iso` needs at this level, then computes it. */
  async compute(iso: number): Promise<IsosurfaceStats> {
    this.#reason = null;
    await this.levels.setIsovalue(iso);
    const shown = this.levels.shown;
    if (!shown || shown.level !== this.level || shown.iso !== iso) {
      throw new LevelStoppedError(this.#reason ?? `level ${this.level}: no surface at isovalue ${iso}`, this.#overBudget);
    }
    // a store without range arrays: its value range is known once a level was resident whole
    if (this.info.valueRange[0] === this.info.valueRange[1]) this.info.valueRange = this.levels.valueRange ?? this.info.valueRange;
    return shown.stats;
  }

  readMesh(): Promise<SurfaceMesh> {
    const shown = this.levels.shown;
    return shown
      ? shown.surface.readMesh()
      : Promise.resolve({ vertices: new Uint32Array(0), indices: new Uint32Array(0), dims: [...this.info.dims] });
  }

  /** Empties the block cache (the pool of compressed chunks stays: that is the network's cache). */
  resetCache(): void {
    this.levels.shown?.surface.resetCache();
  }

  destroy(): void {
    this.levels.destroy();
  }
}
