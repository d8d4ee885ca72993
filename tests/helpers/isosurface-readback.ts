// Test-only readbacks of an Isosurface's internals (the cache's maps and LRU
// order, the per-vertex normals), through its pipeline's parts; they wait for
// the GPU, so the product never calls them.
import { readU32 } from '../../src/gpu/buffers.ts';
import type { Isosurface } from '../../src/isosurface/isosurface.ts';

/** The cache state: slot -> block, block -> slot, and the LRU order (slots, least recently used first). */
export async function readCacheState(
  iso: Isosurface,
): Promise<{ slotToBlock: Uint32Array; blockToSlot: Uint32Array; lruOrder: Uint32Array }> {
  const { device } = iso.pipeline.gpu;
  const { cache } = iso.pipeline.parts;
  const lru = cache.lruLog;
  const [slotToBlock, blockToSlot, log, valid] = await Promise.all([
    readU32(device, cache.slotToBlock, 0, cache.capacity),
    readU32(device, cache.blockToSlot, 0, iso.info.blockCount),
    readU32(device, lru.log, 0, lru.size),
    readU32(device, lru.valid, 0, lru.size),
  ]);
  return { slotToBlock, blockToSlot, lruOrder: log.filter((_, p) => valid[p] === 1) };
}

/** The normals of the drawn surface (u32 octahedral per triangle corner, vertex_format.wgsl), in readVertices' order. */
export async function readNormals(iso: Isosurface): Promise<Uint32Array> {
  return (await iso.pipeline.readSoup()).normals;
}
