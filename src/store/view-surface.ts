// The view's mixed-level surface as one surface for the CLI (`extract` /
// `bench` STORE --view-box or --view): the view stream refined to the whole
// cut for each isovalue, its levels' meshes joined in level-0 voxel index
// space (level L's voxel j at j * 2^L + the level's OME offset), and the cut
// as the record lists it.
import { meshPositions } from '../isosurface/vertex-format.ts';
import type { Isosurface } from '../isosurface/isosurface.ts';
import type { IsosurfaceStats, VolumeInfo } from '../isosurface/types.ts';
import { LevelStoppedError } from './pinned-level.ts';
import type { ChunkIndex } from './types.ts';
import type { ChunkStoreStream } from './gpu-port.ts';

/** One chunk of the cut: its level, chunk coordinates, and the triangles of that level's regular cells whose lowest corner lies in it. */
export interface CutChunkRecord {
  level: number;
  chunk: [number, number, number];
  triangles: number;
}

export class ViewCutSurface {
  readonly info: VolumeInfo;
  #reason: string | null = null;
  #overBudget = false;
  #errors: string[] = [];

  constructor(readonly stream: ChunkStoreStream) {
    const { dims } = stream.levels[0].layout;
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

  get errors(): readonly string[] {
    return this.#errors;
  }

  get memoryBudget(): number {
    return this.stream.budgetBytes;
  }

  /** Refines the view's cut at `iso` to the end; the statistics are the levels' summed. */
  async compute(iso: number): Promise<IsosurfaceStats> {
    this.#reason = null;
    await this.stream.setIsovalue(iso);
    const shown = this.stream.shown;
    if (!shown?.final || shown.iso !== iso)
      throw new LevelStoppedError(this.#reason ?? `the view's cut at isovalue ${iso} was not reached`, this.#overBudget);
    return sumStats(
      iso,
      shown.levels.map((l) => l.stats),
    );
  }

  /** The shown levels' meshes as one, positions in level-0 voxel index space. */
  readPositions(): Promise<{ positions: Float32Array; indices: Uint32Array }> {
    return joinLevelMeshes(this.stream.shown?.levels ?? [], this.stream.store.levelOffsets, this.stream.store.levelScales);
  }

  /** The cut on screen: per drawn chunk that holds part of the surface, its triangles (from the GPU's per-block counts). */
  async cutRecord(): Promise<CutChunkRecord[]> {
    const out: CutChunkRecord[] = [];
    for (const l of this.stream.shown?.levels ?? []) {
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
      for (const [c, t] of [...perChunk].sort((a, b) => a[0] - b[0])) {
        out.push({ level: l.level, chunk: l.volume.chunkCoords(c), triangles: t });
      }
    }
    return out;
  }

  resetCache(): void {
    for (const l of this.stream.shown?.levels ?? []) l.surface.resetCache();
  }

  destroy(): void {
    this.stream.destroy();
  }
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
    vertexBytes: sum((s) => s.vertexBytes),
    gpuMs: sum((s) => s.gpuMs),
    stages: all.flatMap((s) => s.stages),
    timingSource: all[0]?.timingSource ?? 'none',
    grew: all.some((s) => s.grew),
  } as IsosurfaceStats;
}

/** Several levels' meshes as one, positions in level-0 voxel index space (level L's voxel j at j * scale_L + its offset). */
export async function joinLevelMeshes(
  levels: readonly { level: number; surface: Pick<Isosurface, 'readMesh'> }[],
  levelOffsets: readonly [number, number, number][],
  levelScales?: readonly (readonly [number, number, number])[],
): Promise<{ positions: Float32Array; indices: Uint32Array }> {
  const parts: { positions: Float32Array; indices: Uint32Array }[] = [];
  for (const l of levels) {
    const mesh = await l.surface.readMesh();
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
