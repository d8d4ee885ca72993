// The contract between the store side (this folder) and the GPU side
// (src/zfp/chunked-volume.ts, where the types live: the isosurface pipeline,
// a lower layer, reads chunk pools too).
export type { ChunkIndex, ChunkLevelLayout } from '../zfp/chunked-volume.ts';
