// Isosurface.present (src/isosurface/snapshot.ts): the copy drawn while the
// surface computes the next one. After present() the copy's vertices, each
// shard's indices and the draw arguments are the surface's (several index
// shards: a small binding limit); a later computation at another isovalue
// changes the surface, not the copy, until present() again; the mesh an
// export reads (readDrawnMesh) is the copy's; release() keeps only the copy.
import { describe, expect } from 'vitest';
import { readU32 } from '../../../src/gpu/buffers.ts';
import { Isosurface } from '../../../src/isosurface/isosurface.ts';
import type { IsosurfaceDrawData } from '../../../src/isosurface/types.ts';
import { gpuTest } from '../../helpers/gpu.ts';
import { compressVolume, makeField, testKernelOptions } from './helpers.ts';

/** What a draw of `data` draws: per shard its draw arguments' index count and those indices, and the vertices they use. */
async function drawn(device: GPUDevice, data: IsosurfaceDrawData, vertices: number) {
  const shards: { count: number; indices: Uint32Array }[] = [];
  for (const s of data.shards) {
    const args = await readU32(device, s.drawArgs, s.drawArgsOffset, 5);
    shards.push({ count: args[0], indices: args[0] > 0 ? await readU32(device, s.indices, 0, args[0]) : new Uint32Array(0) });
  }
  // shards past the last one in use draw nothing (the copy has only those in use)
  while (shards.length > 1 && shards.at(-1)!.count === 0) shards.pop();
  return { shards, vertices: vertices > 0 ? await readU32(device, data.vertices, 0, 3 * vertices) : new Uint32Array(0) };
}

describe('Isosurface.present', () => {
  gpuTest('the copy draws what the surface drew; the next computation leaves it as it was', async ({ gpu }) => {
    const dims: [number, number, number] = [26, 30, 21];
    const stream = await compressVolume(gpu.device, makeField(dims, 5, 'blobs'), dims, 16);
    // a small binding: the indices come in several shards
    const iso = await Isosurface.create(gpu, stream, { maxVertexBindingBytes: 8 * 777, ...testKernelOptions });
    try {
      expect(iso.presented).toBeNull();
      const [lo, hi] = iso.info.valueRange;
      const a = await iso.compute(lo + 0.45 * (hi - lo));
      expect(a.triangles).toBeGreaterThan(1000);
      expect(iso.pipeline.parts.shards.shards.length).toBeGreaterThan(2);
      const before = await drawn(gpu.device, iso.drawData, a.vertices);
      expect(before.shards.reduce((n, s) => n + s.count, 0)).toBe(a.indices);
      expect(iso.presentBytesNeeded).toBeGreaterThan(0);
      iso.present();
      const copy = iso.presented!;
      expect(copy.vertices).not.toBe(iso.drawData.vertices);
      expect(iso.presentedBytes).toBe(iso.presentBytesNeeded);
      expect(await drawn(gpu.device, copy, a.vertices)).toEqual(before);
      // another isovalue: the surface changes, the copy does not
      const b = await iso.compute(lo + 0.6 * (hi - lo));
      expect(b.indices).not.toBe(a.indices);
      expect(await drawn(gpu.device, copy, a.vertices)).toEqual(before);
      const after = await drawn(gpu.device, iso.drawData, b.vertices);
      expect(after).not.toEqual(before);
      // the mesh drawn (an export) is the copy's: the first surface's mesh, read while the surface holds the second
      const meshA = await iso.readDrawnMesh();
      expect(meshA.indices.length).toBe(a.indices);
      expect(meshA.vertices).toEqual(before.vertices);
      expect(meshA.indices).toEqual(Uint32Array.from(before.shards.flatMap((s) => [...s.indices])));
      // presented again: the copy is the new surface
      iso.present();
      expect(await drawn(gpu.device, iso.presented!, b.vertices)).toEqual(after);
      // released to its copy: the surface computes nothing more, the copy still draws and reads back
      iso.release();
      expect(iso.budgetedBytes).toBe(0);
      await expect(iso.compute(lo + 0.5 * (hi - lo))).rejects.toThrow();
      expect(await drawn(gpu.device, iso.presented!, b.vertices)).toEqual(after);
      expect((await iso.readDrawnMesh()).indices.length).toBe(b.indices);
    } finally {
      iso.destroy();
      stream.destroy();
    }
  });
});
