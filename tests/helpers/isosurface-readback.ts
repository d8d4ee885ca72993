// Test-only readbacks of an Isosurface's internals (the cache's maps and LRU
// order, the per-vertex normals), through its pipeline's parts; they wait for
// the GPU, so the product never calls them.
import { readU32 } from '../../src/gpu/buffers.ts';
import type { Isosurface } from '../../src/isosurface/isosurface.ts';
import { DRAW_ARGS_BYTES } from '../../src/isosurface/layout.ts';

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

/** The normals of the drawn surface (u32 octahedral per vertex, vertex_format.wgsl), in readVertices' order. */
export async function readNormals(iso: Isosurface): Promise<Uint32Array> {
  const { device } = iso.pipeline.gpu;
  const { shards } = iso.pipeline.parts;
  const list = shards.shards;
  const args = await readU32(device, shards.drawArgs, 0, (list.length * DRAW_ARGS_BYTES) / 4);
  const counts = list.map((_, k) => args[4 * k]);
  const out = new Uint32Array(counts.reduce((a, b) => a + b, 0));
  let at = 0;
  for (let k = 0; k < list.length; k++) {
    if (counts[k] === 0) continue;
    out.set(await readU32(device, list[k].normals, 0, counts[k]), at);
    at += counts[k];
  }
  return out;
}
