// A store's stream as one surface for the CLI (`extract` / `bench` STORE):
// each isovalue refined to the end of its plan, whichever planner made it:
// one level pinned (--level L: level L's surface, positions in its own
// voxels) or the view's cut (--view-box / --view: every level the cut uses,
// joined in level-0 voxels, and the cut as the record lists it). The page
// draws the same steps (src/app/store/store-isosurface.ts).
import type { Isosurface } from '../isosurface/isosurface.ts';
import type { IsosurfaceStats, VolumeInfo } from '../isosurface/types.ts';
import { meshPositions } from '../isosurface/vertex-format.ts';
import type { ChunkedVolume } from '../zfp/chunked-volume.ts';
import type { ChunkStoreStream } from './gpu-port.ts';
import type { CutLevelShown } from './stream/stream-types.ts';
import type { ChunkIndex } from './types.ts';

/** The stream could not show a surface at this isovalue (over the budget, a failed chunk): the stream's reason. */
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

/** One chunk of the cut: its level, chunk coordinates, and the triangles of that level's regular cells whose lowest corner lies in it. */
export interface CutChunkRecord {
  level: number;
  chunk: [number, number, number];
  triangles: number;
}

export class StoreStreamSurface {
  readonly info: VolumeInfo;
  /** Isovalues computed together (together()): one refinement draws them all. */
  #together: number[] = [];
  #reason: string | null = null;
  #overBudget = false;
  #errors: string[] = [];

  /** `pinned`: the one level streamed (finest and coarsest), or null: the stream is refined by its view. */
  constructor(
    readonly stream: ChunkStoreStream,
    readonly pinned: number | null,
  ) {
    if (pinned !== null) {
      stream.finest = pinned;
      stream.coarsest = pinned;
    }
    const { dims } = stream.levels[pinned ?? 0].layout;
    const blockGrid = dims.map((n) => Math.ceil(n / 4)) as [number, number, number];
    this.info = {
      dims: [...dims],
      blockGrid,
      blockCount: blockGrid[0] * blockGrid[1] * blockGrid[2],
      valueRange: stream.valueRange ?? [0, 0],
    };
    stream.onProgress((p) => {
      if (p.phase === 'stopped') {
        this.#reason = p.reason ?? 'the refinement stopped';
        this.#overBudget = p.cause === 'budget';
      }
    });
    stream.onError((e) => this.#errors.push(e.message));
  }

  /** Messages of chunks that failed (after their retries), in order. */
  get errors(): readonly string[] {
    return this.#errors;
  }

  get memoryBudget(): number {
    return this.stream.budgetBytes;
  }

  /**
   * Several isovalues drawn together (the page's several surfaces): the
   * first compute() of one of them refines them all at once (a chunk is
   * fetched when any of them needs it; one block cache), and the others are
   * then read from that step without computing again.
   */
  together(isos: readonly number[]): void {
    this.#together = isos.map((v) => Math.fround(v));
  }

  /**
   * Refines `iso` to the end of the plan (the pinned level, or the view's
   * whole cut) and waits for the ranges its surfaces read to be learnt (the
   * next isovalue plans with them); the statistics are the levels' summed.
   */
  async compute(iso: number): Promise<IsosurfaceStats> {
    const f = Math.fround(iso);
    const together = this.#together.includes(f) ? this.#together : [f];
    let shown = this.stream.shown;
    // drawn already with the others of its step
    if (!(this.#reached(shown) && shown!.others.length === together.length - 1 && this.#isoIndex(f) !== undefined)) {
      this.#reason = null;
      await this.stream.setIsovalue(together[0], together.slice(1));
      await this.stream.learnSettled();
      shown = this.stream.shown;
    }
    return this.#statsAt(iso);
  }

  /**
   * The surface at its isovalue refined again where an image's rays found it
   * (StoreStream.setSeen: per level-0 chunk); its stats once that refinement ends.
   */
  async guide(seen: Uint32Array): Promise<IsosurfaceStats> {
    const iso = this.stream.shown?.iso;
    if (iso === undefined) throw new Error('StoreStreamSurface.guide: compute an isovalue first');
    this.#reason = null;
    await this.stream.setSeen(seen);
    await this.stream.learnSettled();
    return this.#statsAt(iso);
  }

  #statsAt(iso: number): IsosurfaceStats {
    const f = Math.fround(iso);
    const shown = this.stream.shown;
    const k = this.#isoIndex(f);
    if (!shown || !this.#reached(shown) || k === undefined) {
      const what =
        this.pinned === null ? `the view's cut at isovalue ${iso} was not reached` : `level ${this.pinned}: no surface at isovalue ${iso}`;
      throw new LevelStoppedError(this.#reason ?? what, this.#overBudget);
    }
    // a store without range arrays: its value range is known once some of its chunks were read
    if (this.info.valueRange[0] === this.info.valueRange[1]) this.info.valueRange = this.stream.valueRange ?? this.info.valueRange;
    return sumStats(
      iso,
      shown.levels.map((l) => (k < 0 ? l.stats : l.others[k].stats)),
    );
  }

  /** Whether the step on screen is the end of the plan (at the pinned level). */
  #reached(shown: ChunkStoreStream['shown']): boolean {
    return !!shown?.final && (this.pinned === null || shown.levels.every((l) => l.level === this.pinned));
  }

  /** Where the step on screen has `iso`: -1 its own isovalue, k its k-th other, undefined not at all. */
  #isoIndex(iso: number): number | undefined {
    return isoIndexOf(this.stream.shown, iso);
  }

  /** The shown levels' meshes at `iso` (default: the step's own) as one: positions in level-0 voxels (a view), or in the pinned level's own voxels. */
  readPositions(iso?: number): Promise<{ positions: Float32Array; indices: Uint32Array }> {
    const k = iso === undefined ? -1 : (this.#isoIndex(Math.fround(iso)) ?? -1);
    const levels = levelsAt(this.stream, this.stream.shown, k);
    const { levelOffsets, levelScales } = this.stream.store;
    if (this.pinned === null) return joinLevelMeshes(levels, levelOffsets, levelScales);
    return joinLevelMeshes(
      levels,
      [],
      levelScales.map(() => [1, 1, 1] as const),
    );
  }

  /**
   * A view's cut on screen: per drawn chunk that holds part of the surface,
   * its triangles (from the GPU's per-block counts); none for a pinned level,
   * nor for the other isovalues of a step (their copies keep no per-block counts).
   */
  async cutRecord(iso?: number): Promise<CutChunkRecord[] | undefined> {
    if (this.pinned !== null) return undefined;
    if (iso !== undefined && this.#isoIndex(Math.fround(iso)) !== -1) return undefined;
    const out: CutChunkRecord[] = [];
    for (const l of this.stream.shown?.levels ?? []) out.push(...(await chunkTriangles(l)));
    return out;
  }

  resetCache(): void {
    for (const l of this.stream.shown?.levels ?? []) l.surface.resetCache();
  }

  destroy(): void {
    this.stream.destroy();
  }
}

/** Where a step has `iso` (float32): -1 its own isovalue, k its k-th other, undefined not at all. */
export function isoIndexOf(shown: { iso: number; others: readonly number[] } | null | undefined, iso: number): number | undefined {
  if (!shown) return undefined;
  if (shown.iso === iso) return -1;
  const k = shown.others.indexOf(iso);
  return k >= 0 ? k : undefined;
}

/** A step's levels at its own isovalue (k = -1) or its k-th other (read from that copy), for joinLevelMeshes. */
export function levelsAt(
  stream: Pick<ChunkStoreStream, 'levels'>,
  shown: ChunkStoreStream['shown'],
  k: number,
): { level: number; surface: Pick<Isosurface, 'readDrawnMesh'> }[] {
  return (shown?.levels ?? []).map((l) => ({
    level: l.level,
    surface: k < 0 ? l.surface : { readDrawnMesh: () => l.others[k].copy.readMesh(stream.levels[l.level].layout.dims) },
  }));
}

/** A shown level's drawn chunks with their triangles (the surface's per-block counts summed per chunk), in chunk order. */
async function chunkTriangles(l: CutLevelShown<ChunkedVolume, IsosurfaceStats, Isosurface>): Promise<CutChunkRecord[]> {
  const { ids, triangles } = await l.surface.readBlockTriangles();
  const per = l.volume.blocksPerChunk;
  const chunkOfSlot = new Map<number, ChunkIndex>();
  for (const c of l.volume.residentChunks()) chunkOfSlot.set(l.volume.slotOfChunk(c)!, c);
  const perChunk = new Map<ChunkIndex, number>(l.drawn.map((c) => [c, 0]));
  for (let i = 0; i < ids.length; i++) {
    const c = chunkOfSlot.get(Math.floor(ids[i] / per));
    if (c === undefined || !perChunk.has(c)) continue;
    perChunk.set(c, perChunk.get(c)! + triangles[i]);
  }
  return [...perChunk].sort((a, b) => a[0] - b[0]).map(([c, t]) => ({ level: l.level, chunk: l.volume.chunkCoords(c), triangles: t }));
}

/** The statistics of a surface made of several levels' surfaces: counts summed, the hit rate weighted by active blocks. */
export function sumStats(iso: number, all: readonly IsosurfaceStats[]): IsosurfaceStats {
  const sum = (f: (s: IsosurfaceStats) => number) => all.reduce((a, s) => a + f(s), 0);
  const active = sum((s) => s.activeBlocks);
  return {
    isovalue: Math.fround(iso),
    activeBlocks: active,
    newBlocks: sum((s) => s.newBlocks),
    occupiedBlocks: sum((s) => s.occupiedBlocks),
    hitRate: active > 0 ? sum((s) => s.hitRate * s.activeBlocks) / active : 1,
    vertices: sum((s) => s.vertices),
    indices: sum((s) => s.indices),
    triangles: sum((s) => s.triangles),
    cacheSlots: sum((s) => s.cacheSlots),
    cacheSlotsUsed: sum((s) => s.cacheSlotsUsed),
    cacheBytes: sum((s) => s.cacheBytes),
    cacheBytesNeeded: sum((s) => s.cacheBytesNeeded),
    vertexBytes: sum((s) => s.vertexBytes),
    gpuMs: sum((s) => s.gpuMs),
    stages: all.flatMap((s) => s.stages),
    timingSource: all[0]?.timingSource ?? 'none',
    grew: all.some((s) => s.grew),
  } as IsosurfaceStats;
}

/**
 * Several levels' drawn meshes as one (the copies a step is drawn from, when
 * it has them: Isosurface.readDrawnMesh), positions in level-0 voxel index
 * space: level L's voxel j at j * scale_L + its offset.
 */
export async function joinLevelMeshes(
  levels: readonly { level: number; surface: Pick<Isosurface, 'readDrawnMesh'> }[],
  levelOffsets: readonly (readonly [number, number, number])[],
  levelScales?: readonly (readonly [number, number, number])[],
): Promise<{ positions: Float32Array; indices: Uint32Array }> {
  const parts: { positions: Float32Array; indices: Uint32Array }[] = [];
  for (const l of levels) {
    const mesh = await l.surface.readDrawnMesh();
    const positions = meshPositions(mesh);
    const k = levelScales?.[l.level] ?? [2 ** l.level, 2 ** l.level, 2 ** l.level];
    const off = levelOffsets[l.level] ?? [0, 0, 0];
    for (let i = 0; i < positions.length; i++) positions[i] = positions[i] * k[i % 3] + off[i % 3];
    parts.push({ positions, indices: mesh.indices });
  }
  const positions = new Float32Array(parts.reduce((a, p) => a + p.positions.length, 0));
  const indices = new Uint32Array(parts.reduce((a, p) => a + p.indices.length, 0));
  let pv = 0;
  let pi = 0;
  for (const p of parts) {
    positions.set(p.positions, pv);
    for (let i = 0; i < p.indices.length; i++) indices[pi + i] = p.indices[i] + pv / 3;
    pv += p.positions.length;
    pi += p.indices.length;
  }
  return { positions, indices };
}
