// What a chunked level is, apart from the GPU: its layout (dims, chunk
// edge and grid, rate, bytes per chunk), chunk indices, the roles a
// resident chunk can play in a surface, and the check that a chunk's bytes
// are a zfp stream of the layout. ChunkedVolume (chunked-volume.ts) holds
// the GPU side.
//
// Roles (setRoles, view-dependent refinement): a level's surface may be
// drawn in some of its resident chunks only. A 'drawn' chunk's cells make
// triangles; a 'ghost' chunk only lends its voxels to the drawn ones (the
// +x/+y/+z and diagonal neighbours of a drawn chunk, so that the drawn
// chunk's cells on its upper faces are complete, exactly the level's cells):
// its blocks stay active, its cells make no triangles, and only its cells on
// the chunk's three lower faces keep the vertices they own, the only ones a
// drawn neighbour's triangles can use; an 'idle' chunk is kept in the pool
// but unused (never active, its voxels never read). A 'skirt' (setRoles
// with { skirts: true }: every ghost is one) is a ghost whose cells next to
// a drawn chunk also make triangles: for each axis a whose lower neighbour
// G - e_a is drawn, the skirt G's one layer of cells of chunk-local
// coordinate 0 on a (a one-cell overlap of a drawn region into its +side
// neighbour, drawn at another level, that covers the crack between levels);
// it keeps the cases of its layers 0 and 1 on such an axis too, for the
// vertices those cells index. The role rides in the top 2 bits of the
// chunk's slot-table word, chunk | role << 30 (drawn 0, ghost 1, idle 2,
// skirt 3; an empty slot stays 0xffffffff, never a skirt's word as chunk
// indices stay below 2^30 - 1), so the tables keep their 8 bytes per chunk
// and the kernels their bindings
// (shaders/isosurface/blocks_pool.wgsl); a pool that never sets roles
// writes the words it always did. Role changes write only the words that
// change and log no slot change: nothing decoded depends on a role.
import { formatDims } from '../core/naming.ts';
import { openZfpStream, planZfpStream } from './format.ts';

/** One level of a chunked zfp store, as the GPU side needs it (facts only, no UI wording). */
export interface ChunkLevelLayout {
  /** Voxels of this level, x, y, z (x fastest). */
  dims: [number, number, number];
  /** Chunk edge C in voxels (a multiple of 4; chunks are C^3, edge chunks stored at full size). */
  chunkEdge: number;
  /** ceil(dims / C) per axis, x, y, z. */
  chunkGrid: [number, number, number];
  /** zfp fixed rate in bits per value. */
  rate: number;
  /** Bytes of one chunk as stored: a zfp stream with its header, identical for every chunk. */
  chunkBytes: number;
  /** For messages: the store and level, e.g. "http://host/bonsai.zarr level 1". */
  name: string;
  /**
   * What put() receives: 'zfp' (default) the chunk's stream as stored;
   * 'float32' its C^3 values (x fastest), encoded on the GPU into the slot
   * (stores of lossless chunks, src/store/zarr/source-store.ts). The slot
   * holds the same zfp stream either way (chunkBytes).
   */
  arrivesAs?: 'zfp' | 'float32';
}

/** Chunk index = cx + gx * (cy + gy * cz) with (gx, gy, gz) = chunkGrid. */
export type ChunkIndex = number;

/**
 * What a chunk does for the level's surface (setRoles): 'drawn' its cells
 * make triangles; 'ghost' it lends its voxels (and the vertices its cells on
 * its lower faces own) to drawn neighbours, no triangles; 'idle' resident
 * but unused; 'skirt' a ghost whose cells of chunk-local coordinate 0 on an
 * axis whose lower neighbour is drawn also make triangles (setRoles'
 * `skirts`).
 */
export type ChunkRole = 'drawn' | 'ghost' | 'idle' | 'skirt';

/** A role's code in the top bits of a slot-table word (ROLE_* in shaders/isosurface/common.wgsl). */
export const CHUNK_ROLE_CODES: Readonly<Record<ChunkRole, number>> = { drawn: 0, ghost: 1, idle: 2, skirt: 3 };

/** setRoles' options. */
export interface ChunkRoleOptions {
  /**
   * Every ghost a 'skirt' (default false): a ghost chunk G whose lower
   * neighbour G - e_a on an axis a is drawn also makes the triangles of
   * its cells of chunk-local coordinate 0 on a (the level's own triangles
   * of those cells), a one-cell overlap of the drawn region into its
   * +side neighbour, which is drawn at another level.
   */
  skirts?: boolean;
}
/**
 * Slot-table word = chunk + role code * 2^ROLE_SHIFT: chunk indices stay
 * below 2^30 - 1 (create), so a skirt's word (code 3) is never an empty
 * slot's 0xffffffff.
 */
export const ROLE_SHIFT = 30;

/** A chunk that cannot go into the pool (wrong bytes, pool full), or a layout that cannot be pooled. */
export class ChunkError extends Error {
  constructor(
    message: string,
    readonly chunk?: [number, number, number],
  ) {
    super(message);
    this.name = 'ChunkError';
  }
}

/** Throws a ChunkError unless `bytes` are a zfp fixed-rate stream of one chunk of `layout` (its blocks of `bitsPerBlock`, after `headerBits`). */
export function checkChunkStream(
  layout: ChunkLevelLayout,
  bitsPerBlock: number,
  headerBits: number,
  bytes: Uint8Array,
  where: string,
  at: [number, number, number],
): void {
  const edge = layout.chunkEdge;
  if (bytes.byteLength !== layout.chunkBytes) {
    throw new ChunkError(
      `${where}: ${bytes.byteLength} bytes, but a ${edge}^3 chunk at rate ${layout.rate} is ${layout.chunkBytes} bytes`,
      at,
    );
  }
  let info;
  try {
    info = openZfpStream(bytes, where);
  } catch (e) {
    throw new ChunkError((e as Error).message, at);
  }
  if (!info.hasHeader || info.dims.some((n) => n !== edge) || info.bitsPerBlock !== bitsPerBlock || info.payloadBitOffset !== headerBits) {
    throw new ChunkError(
      `${where}: the chunk's zfp header says ${formatDims(info.dims)} at ${info.mode}; the level's chunks are ${edge}^3 at rate ${layout.rate}`,
      at,
    );
  }
}

/**
 * Throws a ChunkError (naming the level) when `layout` is inconsistent
 * (chunk edge, grid, bytes) or a pool of `poolChunks` of it cannot be
 * addressed on a device of `limits`.
 */
export function checkChunkLayout(
  layout: ChunkLevelLayout,
  poolChunks: number,
  limits: Pick<GPUSupportedLimits, 'maxStorageBufferBindingSize' | 'maxBufferSize'>,
): void {
  const { dims, chunkEdge: edge, chunkGrid, rate, chunkBytes, name } = layout;
  const fail = (what: string): never => {
    throw new ChunkError(`${name}: ${what}`);
  };
  if (!dims.every((n) => Number.isInteger(n) && n >= 1)) fail(`impossible dimensions ${dims.join('x')}`);
  if (!Number.isInteger(edge) || edge < 4 || edge % 4 !== 0 || edge > 256)
    fail(`the chunk edge ${edge} is not a multiple of 4 between 4 and 256`);
  if (!chunkGrid.every((g, i) => g === Math.ceil(dims[i] / edge)))
    fail(`the chunk grid ${chunkGrid.join('x')} does not cover ${formatDims(dims)} in chunks of ${edge}`);
  let planned;
  try {
    planned = planZfpStream(`${name} chunk`, [edge, edge, edge], rate, true);
  } catch (e) {
    fail((e as Error).message);
  }
  if (chunkBytes !== planned!.paddedBytes)
    fail(`a ${edge}^3 chunk at rate ${rate} is ${planned!.paddedBytes} bytes as zfp writes it, not ${chunkBytes}`);
  if (!Number.isInteger(poolChunks) || poolChunks < 1) fail(`the pool must hold at least one chunk (got ${poolChunks})`);
  // a level may have any number of blocks (2^36 for 16384^3): the pipeline names blocks by pool id
  // the level's tables are one storage binding; a chunk's bit offsets are 32-bit in WGSL
  const chunks = chunkGrid[0] * chunkGrid[1] * chunkGrid[2];
  const binding = Math.min(limits.maxStorageBufferBindingSize, limits.maxBufferSize);
  if (chunks * 8 > binding)
    fail(
      `${chunks} chunks need ${chunks * 8} bytes of tables (chunk -> slot, slot -> chunk), more than one storage binding of this device (${binding} bytes: maxStorageBufferBindingSize); convert with larger chunks`,
    );
  // the slot table keeps a chunk's role in the top 2 bits of its word; one
  // binding (at most 4 GiB) holds fewer than 2^29 chunks, so this never fails.
  // Chunk indices then stay below 2^30 - 1: a skirt's word, chunk + 3 * 2^30,
  // is never NONE (0xffffffff, an empty slot)
  if (chunks >= 2 ** ROLE_SHIFT) fail(`${chunks} chunks: the slot table holds chunk indices below 2^${ROLE_SHIFT}`);
  if (Math.min(poolChunks, chunks) * (edge / 4) ** 3 >= 2 ** 32)
    fail(`a pool of ${poolChunks} chunks of ${edge}^3 has more block ids than 32 bits hold`);
  if (chunkBytes * 8 >= 2 ** 32) fail(`a chunk of ${chunkBytes} bytes is too large to address in 32-bit bit offsets`);
}

/** The role of every chunk of a level in its surface: ChunkedVolume.setRoles' state. */
export class ChunkRoles {
  #drawn: ReadonlySet<ChunkIndex> | null = null;
  #ghosts: ReadonlySet<ChunkIndex> = new Set();
  #skirts = false;

  /**
   * `drawn` null (the default): every chunk is drawn. Otherwise a chunk in
   * `drawn` is drawn, one in `ghosts` (and not in `drawn`) a ghost, any
   * other idle (ChunkRole). The sets are copied. A drawn chunk's cells on
   * its upper faces are complete when its +x, +y, +z and diagonal
   * neighbours (those of the level) are resident and drawn or ghosts; next
   * to one that is not resident or idle, its cells within two cells of that
   * face make no triangle (their edges' owners would read it).
   *
   * With `options.skirts` every ghost is a 'skirt' instead: its cells of
   * chunk-local coordinate 0 on an axis a whose chunk below on a (G - e_a)
   * is drawn make triangles too (the level's triangles of those cells: the
   * statistics and readBlockTriangles count them, in the skirt's blocks);
   * such a cell is complete when the skirt's +b, +c and diagonal (b, c)
   * neighbours are resident and not idle, as they are when the ghosts are
   * the drawn chunks' neighbours above; next to one that is not, the cell
   * makes no triangle, as a drawn cell. A skirt with no drawn chunk below
   * it is a ghost.
   */
  set(drawn: ReadonlySet<ChunkIndex> | null, ghosts: ReadonlySet<ChunkIndex>, options: ChunkRoleOptions = {}): void {
    this.#drawn = drawn ? new Set(drawn) : null;
    this.#ghosts = drawn ? new Set(ghosts) : new Set();
    this.#skirts = options.skirts ?? false;
  }

  of(chunk: ChunkIndex): ChunkRole {
    if (this.#drawn === null || this.#drawn.has(chunk)) return 'drawn';
    if (!this.#ghosts.has(chunk)) return 'idle';
    return this.#skirts ? 'skirt' : 'ghost';
  }
}
