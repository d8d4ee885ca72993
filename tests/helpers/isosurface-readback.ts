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

/**
 * The drawn surface as a triangle soup: per triangle corner its vertex's
 * position words (edge and fraction; block coordinates) and its normal (u32 octahedral,
 * vertex_format.wgsl), in index order.
 */
export async function readSoup(iso: Pick<Isosurface, 'readMesh'>): Promise<{ vertices: Uint32Array; normals: Uint32Array }> {
  const mesh = await iso.readMesh();
  const n = mesh.indices.length;
  const vertices = new Uint32Array(2 * n);
  const normals = new Uint32Array(n);
  for (let i = 0; i < n; i++) {
    const v = mesh.indices[i];
    vertices[2 * i] = mesh.vertices[3 * v];
    vertices[2 * i + 1] = mesh.vertices[3 * v + 1];
    normals[i] = mesh.vertices[3 * v + 2];
  }
  return { vertices, normals };
}

/** The position word pairs (edge and fraction; block coordinates) of the drawn surface's triangle corners. */
export async function readVertices(iso: Pick<Isosurface, 'readMesh'>): Promise<Uint32Array> {
  return (await readSoup(iso)).vertices;
}

/** The normals of the drawn surface, in readVertices' order. */
export async function readNormals(iso: Pick<Isosurface, 'readMesh'>): Promise<Uint32Array> {
  return (await readSoup(iso)).normals;
}
