// What the view cut (cut.ts) takes and gives: the store's levels, the camera,
// the tolerance, the budget, and the leaves and per-level sets of the cut.
import type { ChunkIndex } from '../types.ts';

/** One level of the store, as the cut needs it. */
export interface CutLevel {
  /** Voxels of this level, x, y, z. */
  dims: [number, number, number];
  /** Chunk edge in this level's voxels (chunks are cubes). */
  chunkEdge: number;
  /** ceil(dims / chunkEdge) per axis. */
  chunkGrid: [number, number, number];
  /** Level-0 voxels one voxel of this level spans, x, y, z (default 2^L on every axis; a level may halve only some axes). */
  scale?: readonly [number, number, number];
}

/** The camera the cut sees. */
export interface CutCamera {
  /**
   * World -> clip, column-major 4x4 (gl-matrix mat4), WebGPU clip space (x, y
   * in [-w, w], z in [0, w]). World: level-0 voxel (i, j, k) at (i*sx, j*sy,
   * k*sz), voxelSize = [sx, sy, sz] (the page's world, see the top of cut.ts).
   */
  viewProj: ArrayLike<number>;
  /** The eye in world coordinates. */
  eye: [number, number, number];
  /** Pixels per world unit at distance 1 along the view: viewportHeightPx / (2 tan(fovY / 2)) (perspective). */
  pixelsPerUnit: number;
  /**
   * What the view is framed on: the point the camera looks at (the page's
   * orbit target, the centre of `--view-box`) and a radius about it (half
   * the view's half-height there). A budget that binds is spent first on the
   * regions in the cone from the eye through that sphere (the middle of the
   * screen), nearer before farther, then on the others, nearer the middle
   * first. Without one, by error alone.
   */
  focus?: { point: [number, number, number]; radius: number };
}

export interface CutInput {
  /** Every level of the store, 0 (finest) first. */
  levels: CutLevel[];
  /** World size of a level-0 voxel. */
  voxelSize: [number, number, number];
  camera: CutCamera;
  /** A region is refined while one of its voxels projects to more than this many pixels (callers: about 1.5). */
  tolerancePx: number;
  /** The finest level the cut may use. */
  finest: number;
  /** The coarsest level the cut may use: its chunks are the roots. */
  coarsest: number;
  /**
   * Per level, which of its chunks the surface needs (the isovalue's plan), or
   * null when that level's chunk ranges are not known yet: the cut then does
   * not refine into that level and lists it in `wantsRanges`. (When the
   * coarsest level's is null, all its drawn and ghost chunks count as wanted,
   * and it is listed too.) Called once per level.
   */
  needs: (level: number) => ((chunk: ChunkIndex) => boolean) | null;
  /** GPU bytes one wanted chunk of level L costs (pool slot + per-block state + a share of the surface). Called once per level. */
  chunkBytes: (level: number) => number;
  /** What the wanted chunks of all levels may cost together (Infinity: no limit). */
  budgetBytes: number;
  /**
   * A cut for rays (issue 46): per chunk of level 0 (x fastest), 1 + the
   * pixels whose first hit lies in it, 1 where none does but one lies near
   * (a little before or after along its ray, below a seam: seen.ts), 0
   * elsewhere. The cut then refines only nodes holding a seen chunk (where a
   * budget binds, those more pixels hit first), draws only the seen children of a split, keeps the node
   * drawn for the rest of its region (the cut is nested: regions.ts says which
   * level owns what), and is not 2:1 balanced. Absent: the cut by the view alone.
   */
  seen?: Uint32Array | null;
}

/** A leaf of the cut: one chunk drawn at its level. */
export interface CutNode {
  level: number;
  chunk: ChunkIndex;
  /** The chunk's coordinates in its level's chunk grid. */
  coords: [number, number, number];
  /** Projected size of one of its voxels at its nearest point, in pixels (Infinity with the eye inside). */
  errorPx: number;
  /** World distance from the eye to its box (0 inside). */
  distance: number;
  /** Whether its box meets the view frustum (conservative test). */
  inView: boolean;
}

export interface CutLevelSets {
  /** Leaf chunks at this level (needed or not), ascending; in a cut for rays also the chunks split with some children undrawn. */
  drawn: ChunkIndex[];
  /**
   * Chunks the surface needs that are not drawn but have a drawn chunk among
   * their 7 lower neighbours (c - {0,1}^3 minus c: the drawn chunk's cells on
   * its upper faces read their voxels), ascending; none in a nested cut (`ViewCut.nested`).
   */
  ghosts: ChunkIndex[];
  /** needed ∩ (drawn ∪ ghosts), nearest to the eye first (ties: ascending chunk). */
  wanted: ChunkIndex[];
}

export interface ViewCut {
  /** The leaves, nearest to the eye first (ties: level, chunk): every region of the volume at exactly one level. */
  nodes: CutNode[];
  /** Per level (index = level; empty outside finest..coarsest). */
  levels: CutLevelSets[];
  /** Σ over levels of wanted.length * chunkBytes(level). */
  bytes: number;
  /**
   * A cut for rays (`CutInput.seen`): nested (every drawn chunk's coarser
   * ancestors drawn too) and without ghosts: where a drawn chunk's next chunk
   * is not drawn, the level owning the region there traces the drawn chunk's
   * last cells from its own voxels (shaders/render/ray_blocks_pool.wgsl).
   */
  nested: boolean;
  /** True when some region would have been refined but the budget refused it (or the coarsest level alone is over it). */
  limitedByBudget: boolean;
  /** Levels the cut would have refined into but whose `needs` is null (and the coarsest when its needs is null), ascending. */
  wantsRanges: number[];
  /** Facts worth telling: levels that cannot be refined (chunks that do not nest), a budget the coarsest level alone exceeds. */
  notes: string[];
}

/** A view a store is refined by: the camera and the screen-space tolerance. */
export interface ViewSpec {
  camera: CutCamera;
  /** A region is refined while one of its voxels projects to more than this many pixels. */
  tolerancePx: number;
}

/** Default screen-space tolerance in pixels. */
export const DEFAULT_TOLERANCE_PX = 1.5;
