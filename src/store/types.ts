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
}
/** Chunk index = cx + gx * (cy + gy * cz) with (gx, gy, gz) = chunkGrid. */
export type ChunkIndex = number;
