/** A chunk the GPU side refuses (wrong header, rate or size, pool full), naming the store level and the chunk. */
export class ChunkError extends Error {
  constructor(
    message: string,
    /** The level's name (ChunkLevelLayout.name). */
    readonly level: string,
    /** The chunk's (x, y, z) in the chunk grid. */
    readonly chunk: [number, number, number],
  ) {
    super(message);
    this.name = 'ChunkError';
  }
}
